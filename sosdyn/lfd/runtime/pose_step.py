"""One pose at a time, in plain floats: the chart and the velocities of :class:`~sosdyn.lfd.model.pose.PoseCDSP`'s
predictor for a control loop (scipy's ``Rotation`` costs ~0.1 ms a call; these, a few microseconds).

The same formulas as :mod:`sosdyn.lfd.data.poses` (and the C++ export), on one unit quaternion (w, x, y, z):

    r = log(R_g^T R):  p = conj(g) q (sign chosen with p_w >= 0), r = 2 atan2(|p_v|, p_w) p_v / |p_v|  (|r| in [0, pi])
    J_r(r) d = d - a r x d + b r x (r x d),  t = |r|, a = (1 - cos t)/t^2, b = (t - sin t)/t^3 (series below SMALL_ANGLE)
    omega = R (J_r(r) d) = q (J_r d) conj(q)

equal to the scipy path to rounding (tested).
"""
from __future__ import annotations

import math

from ..data.poses import SMALL_ANGLE


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def chart_one(q, g) -> tuple:
    """r = log(R_g^T R) of the unit quaternions q and g (sequences of 4 floats, w x y z)."""
    w = g[0] * q[0] + g[1] * q[1] + g[2] * q[2] + g[3] * q[3]
    v = (g[0] * q[1] - g[1] * q[0] - g[2] * q[3] + g[3] * q[2],
         g[0] * q[2] + g[1] * q[3] - g[2] * q[0] - g[3] * q[1],
         g[0] * q[3] - g[1] * q[2] + g[2] * q[1] - g[3] * q[0])
    if w < 0.0:
        w, v = -w, (-v[0], -v[1], -v[2])
    s = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    f = 2.0 / w if s < 1e-12 else 2.0 * math.atan2(s, w) / s
    return (f * v[0], f * v[1], f * v[2])


def body_velocity_one(r, d) -> tuple:
    """J_r(r) d for one rotation vector r and chart velocity d."""
    t = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    if t < SMALL_ANGLE:
        a, b = 0.5 - t * t / 24.0, 1.0 / 6.0 - t * t / 120.0
    else:
        a, b = (1.0 - math.cos(t)) / (t * t), (t - math.sin(t)) / (t * t * t)
    rxd = _cross(r, d)
    rrxd = _cross(r, rxd)
    return tuple(d[i] - a * rxd[i] + b * rrxd[i] for i in range(3))


def rotate_one(q, v) -> tuple:
    """R v for the unit quaternion q (w x y z): v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)."""
    u = (q[1], q[2], q[3])
    uv = _cross(u, v)
    uuv = _cross(u, uv)
    return tuple(v[i] + 2.0 * (q[0] * uv[i] + uuv[i]) for i in range(3))

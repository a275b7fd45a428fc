"""A fitted :class:`~sosdyn.lfd.model.pose.PoseCDSP` at run time: the chart's angular velocity
(:func:`body_velocity`), the speed limits (:func:`pose_speed_factor`), one pose in plain floats for the
predictor (:func:`chart_one`, :func:`body_velocity_one`, :func:`rotate_one`), and standalone code: Python
``predict_pose(x, quat, goal=None)`` (:func:`pose_to_python`) or C++17 ``predict_pose(x, quat, v, omega, goal =
nullptr)`` (:func:`pose_to_cpp`).

The chart and velocities (docs/theory.md, "Poses"), on unit quaternions (w, x, y, z):

    r = log(R_g^T R):  p = conj(g) q (sign chosen with p_w >= 0), r = 2 atan2(|p_v|, p_w) p_v / |p_v|  (|r| in [0, pi])
    J_r(r) d = d - a r x d + b r x (r x d),  t = |r|, a = (1 - cos t)/t^2, b = (t - sin t)/t^3 (series below SMALL_ANGLE)
    omega = R (J_r(r) rdot) = q (J_r rdot) conj(q)

(R^T Rdot = [J_r(r) rdot]_x for R = R_g exp(r)). The one-pose functions write them in plain floats (scipy's
``Rotation`` costs ~0.1 ms a call; these, microseconds), equal to the scipy path to rounding (tested).

Exports: each block is its CDSP's own export (:func:`~sosdyn.lfd.runtime.export_python.to_python` /
:func:`~sosdyn.lfd.runtime.export_cpp.to_cpp`): the position block's ``predict(x, goal)`` and the orientation
block's ``predict(r, 0)``, then the chart (the half turn takes either logarithm), v = xdot, omega = R J_r(r) rdot
(:func:`body_velocity`, its source copied verbatim into the Python). Speed limits (``max_speed`` on |v|,
``max_angular_speed`` on |omega|, written into the code): (v, omega) scaled by one smooth factor, the speed
limit's (:mod:`.states`, embedded in each block's code) of the joint ratio of |v| / v_max and |omega| / w_max,
as :meth:`~sosdyn.lfd.model.pose.PoseCDSP.predictor`. Every orientation has a velocity: no
state is refused but one that is not finite or a quaternion whose norm is not in (0.5, 1.5) (Python:
ValueError; C++: false).

The Python module needs numpy and scipy, never sosdyn; each block's module is embedded as a string
literal (``repr``: no text of the model reaches the file unescaped) and run into its own namespace. The
C++ header holds the blocks' namespaces NS_position and NS_orientation and NS_pose with ``predict_pose`` (NS and the part joined by one underscore: ``abc_`` gives ``abc_pose``)
in plain arithmetic (<cmath> only): quaternion product and conjugate, log and the right Jacobian.
"""
from __future__ import annotations

import inspect
import math

import numpy as np

from .codegen import _flat, _literal, check_namespace
from .export_cpp import to_cpp
from .export_python import to_python
from .states import check_max_speed, joint_ratio, saturation_factor, speed_ratio

SMALL_ANGLE = 1e-4            # below this |r| the right Jacobian's series is used
UNIT_RANGE = (0.5, 1.5)       # accepted quaternion norms (renormalised), as PoseCDSP's inputs


def body_velocity(r, rdot) -> np.ndarray:
    """J_r(r) rdot row by row (m, 3): rdot - a r x rdot + b r x (r x rdot), t = |r|, a = (1 - cos t)/t^2,
    b = (t - sin t)/t^3 (series below SMALL_ANGLE); J_r is the right Jacobian of SO(3), so
    R^T Rdot = [J_r(r) rdot]_x for R = R_g exp(r): the body angular velocity."""
    r, d = np.atleast_2d(np.asarray(r, dtype=float)), np.atleast_2d(np.asarray(rdot, dtype=float))
    t = np.linalg.norm(r, axis=1, keepdims=True)
    small = t < SMALL_ANGLE
    ts = np.where(small, 1.0, t)
    a = np.where(small, 0.5 - t * t / 24.0, (1.0 - np.cos(ts)) / ts**2)
    b = np.where(small, 1.0 / 6.0 - t * t / 120.0, (ts - np.sin(ts)) / ts**3)
    rxd = np.cross(r, d)
    return d - a * rxd + b * np.cross(r, rxd)


def pose_speed_factor(R, Sdot, max_speed, max_angular_speed) -> np.ndarray:
    """lambda (m, 1) at the rotation vectors R (m, 3) for the chart velocities Sdot (m, 6): the speed limit's
    factor (:mod:`.states`) of the joint ratio of |v| / v_max and |omega| / w_max (:func:`~.states.joint_ratio`),
    v = sdot_x, |omega| = |R J_r(r) rdot| = |J_r(r) rdot| (R orthogonal). One positive factor on the whole
    velocity keeps the chart paths and the goal (docs/theory.md); |v| < v_max and |omega| < w_max."""
    w = body_velocity(R, Sdot[:, 3:])
    rho = joint_ratio([None if max_speed is None else speed_ratio(Sdot[:, :3], max_speed),
                       None if max_angular_speed is None else speed_ratio(w, max_angular_speed)])
    return np.broadcast_to(saturation_factor(rho), (len(R),))[:, None]


def check_limits(max_speed, max_angular_speed) -> tuple:
    """(max_speed, max_angular_speed), each None or a finite number > 0 (InputError otherwise)."""
    return check_max_speed(max_speed), check_max_speed(max_angular_speed, "max_angular_speed", "rad/s")


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


def pose_to_python(model, max_speed: float | None = None, max_angular_speed: float | None = None) -> str:
    """Source of the standalone pose module (module docstring)."""
    max_speed, max_angular_speed = check_limits(max_speed, max_angular_speed)
    return f'''# Standalone evaluator of a sosdyn PoseCDSP (position block + orientation block); numpy and scipy only.
# v = xdot (position block), omega = R J_r(r) rdot (orientation block), r = log(R_g^T R).
"""Standalone evaluator of a PoseCDSP: predict_pose(x, quat, goal=None) -> (v, omega)."""
import types

import numpy as np
from scipy.spatial.transform import Rotation


def _block(name, source):
    """The block's own standalone evaluator (sosdyn's CDSP export), run into its own namespace."""
    module = types.ModuleType(name)
    exec(compile(source, "<" + name + " block>", "exec"), module.__dict__)  # noqa: S102 -- the literal below
    return module


position = _block("position", {to_python(model.position_)!r})
orientation = _block("orientation", {to_python(model.orientation_)!r})

GOAL_QUAT = np.array({_literal(model.goal_quat_)})   # w x y z
GOAL = np.concatenate([position.GOAL, GOAL_QUAT])    # the model's goal pose
SMALL_ANGLE = {SMALL_ANGLE!r}
POSE_MAX_SPEED = {max_speed!r}                  # None, or the largest |v| (units/s)
POSE_MAX_ANGULAR_SPEED = {max_angular_speed!r}  # None, or the largest |omega| (rad/s): (v, omega) scaled by one factor
UNIT_RANGE = {UNIT_RANGE!r}                     # accepted quaternion norms (renormalised)
_ORIGIN = np.zeros(3)


{inspect.getsource(body_velocity)}

def _unit(q, what):
    q = np.asarray(q, dtype=float)
    if q.shape != (4,) or not np.isfinite(q).all() or not UNIT_RANGE[0] < np.linalg.norm(q) < UNIT_RANGE[1]:
        raise ValueError(what + " must be a finite unit quaternion (w, x, y, z)")
    return q / np.linalg.norm(q)


def predict_pose(x, quat, goal=None):
    """(v, omega): linear velocity (3,) and world angular velocity (3,) at the position x (3,) and the
    orientation quat (4,, w x y z), for the goal pose (x, y, z, qw, qx, qy, qz) or the model's."""
    x = np.asarray(x, dtype=float)
    if x.shape != (3,) or not np.isfinite(x).all():
        raise ValueError("x must be 3 finite numbers")
    goal = GOAL if goal is None else np.asarray(goal, dtype=float)
    if goal.shape != (7,) or not np.isfinite(goal).all():
        raise ValueError("goal must be 7 finite numbers (x, y, z, qw, qx, qy, qz)")
    R = Rotation.from_quat(_unit(quat, "quat"), scalar_first=True)
    r = (Rotation.from_quat(_unit(goal[3:], "the goal's quaternion"), scalar_first=True).inv() * R).as_rotvec()
    v = position.predict(x, goal[:3])
    omega = R.apply(body_velocity(r, orientation.predict(r, _ORIGIN))[0])
    scale = float(position.saturation_factor(position.joint_ratio([None if limit is None else position.speed_ratio(
        u, limit) for limit, u in ((POSE_MAX_SPEED, v), (POSE_MAX_ANGULAR_SPEED, omega))])))
    return scale * v, scale * omega
'''


def _cpp_ratio(limit: float | None, pointer: str, namespace: str) -> str:
    """A C++ expression: |vector| / limit of the 3 doubles at ``pointer`` (the speed limit's
    :func:`~.states.speed_ratio`, the block header's ``speed_ratio``), 0 without a limit."""
    return "0.0" if limit is None else f"{namespace}::speed_ratio({pointer}, 3, {limit!r}, top, norm)"


def pose_to_cpp(model, namespace: str = "pose_model", max_speed: float | None = None,
                max_angular_speed: float | None = None) -> str:
    """Source of the header-only C++17 pose evaluator (module docstring): namespaces ``namespace``
    + _position, _orientation and _pose (``predict_pose``), joined by one underscore (a ``namespace`` that
    ends with one takes none more: ``abc_`` gives ``abc_pose``, never the reserved ``abc__pose``)."""
    max_speed, max_angular_speed = check_limits(max_speed, max_angular_speed)
    namespace = check_namespace(namespace, "pose_model")
    stem = namespace if namespace.endswith("_") else namespace + "_"
    pos_ns, ori_ns, pose_ns = f"{stem}position", f"{stem}orientation", f"{stem}pose"
    blocks = to_cpp(model.position_, pos_ns) + to_cpp(model.orientation_, ori_ns)
    limits = (("  double top, norm;   // scratch of speed_ratio\n" if (max_speed, max_angular_speed) != (None, None) else "")
              + f"  const double speed = {_cpp_ratio(max_speed, 'v', pos_ns)};\n"
              f"  const double turn = {_cpp_ratio(max_angular_speed, 'w_out.data()', pos_ns)};\n"
              f"  const double scale = {pos_ns}::joint_factor(speed, turn);   // |v| < max_speed, |omega| < max_angular_speed\n")
    lo, hi = UNIT_RANGE
    return blocks + f"""
namespace {pose_ns} {{

constexpr std::array<double, 4> goal_quat = {{{_flat(model.goal_quat_)}}};   // w x y z
constexpr double small_angle = {SMALL_ANGLE!r};

inline std::array<double, 4> qmul(const double* a, const double* b) {{
  return {{a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]}};
}}

// r = log(q) for a unit quaternion (sign chosen with w >= 0), |r| in [0, pi].
inline std::array<double, 3> qlog(std::array<double, 4> q) {{
  if (q[0] < 0) for (double& c : q) c = -c;
  const double s = std::sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  const double f = s < 1e-12 ? 2.0 / q[0] : 2.0 * std::atan2(s, q[0]) / s;
  return {{f * q[1], f * q[2], f * q[3]}};
}}

// (v, omega) at the position x[3] and orientation quat[4] (w x y z) for the goal pose goal[7] (or the
// model's): v = xdot, omega = R J_r(r) rdot, r = log(R_g^T R); false if an input or the result is not
// finite or a quaternion's norm is outside ({lo}, {hi}). Every orientation has a velocity.
inline bool predict_pose(const double* x, const double* quat, double* v, double* omega, const double* goal = nullptr) {{
  const double* gx = goal ? goal : {pos_ns}::goal.data();
  const double* gq = goal ? goal + 3 : goal_quat.data();
  double qn = 0.0, gn = 0.0;
  for (int i = 0; i < 4; ++i) {{ qn += quat[i] * quat[i]; gn += gq[i] * gq[i]; }}
  qn = std::sqrt(qn);
  gn = std::sqrt(gn);
  if (!(qn > {lo} && qn < {hi} && gn > {lo} && gn < {hi})) return false;
  const std::array<double, 4> q = {{quat[0] / qn, quat[1] / qn, quat[2] / qn, quat[3] / qn}};
  const std::array<double, 4> gc = {{gq[0] / gn, -gq[1] / gn, -gq[2] / gn, -gq[3] / gn}};
  const std::array<double, 3> r = qlog(qmul(gc.data(), q.data()));
  const double origin[3] = {{0.0, 0.0, 0.0}};
  std::array<double, 3> d{{}};
  if (!{pos_ns}::predict(x, v, gx) || !{ori_ns}::predict(r.data(), d.data(), origin)) return false;
  const double t = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  const double a = t < small_angle ? 0.5 - t * t / 24.0 : (1.0 - std::cos(t)) / (t * t);
  const double b = t < small_angle ? 1.0 / 6.0 - t * t / 120.0 : (t - std::sin(t)) / (t * t * t);
  const std::array<double, 3> rxd = {{r[1] * d[2] - r[2] * d[1], r[2] * d[0] - r[0] * d[2], r[0] * d[1] - r[1] * d[0]}};
  const std::array<double, 3> rxrxd = {{r[1] * rxd[2] - r[2] * rxd[1], r[2] * rxd[0] - r[0] * rxd[2],
                                       r[0] * rxd[1] - r[1] * rxd[0]}};
  std::array<double, 4> wb = {{0.0, 0.0, 0.0, 0.0}};   // body angular velocity J_r(r) d, as a pure quaternion
  for (int i = 0; i < 3; ++i) wb[1 + i] = d[i] - a * rxd[i] + b * rxrxd[i];
  const std::array<double, 4> qc = {{q[0], -q[1], -q[2], -q[3]}};
  const std::array<double, 4> qw = qmul(q.data(), wb.data());
  const std::array<double, 4> w = qmul(qw.data(), qc.data());     // omega = R omega_b = q omega_b q*
  const std::array<double, 3> w_out = {{w[1], w[2], w[3]}};
  // speed limits: one smooth factor on (v, omega), the speed limit's of their joint ratio
{limits}  bool finite = true;
  for (int i = 0; i < 3; ++i) {{
    v[i] *= scale;
    omega[i] = scale * w_out[i];
    finite = finite && std::isfinite(v[i]) && std::isfinite(omega[i]);
  }}
  return finite;
}}

}}  // namespace {pose_ns}
"""

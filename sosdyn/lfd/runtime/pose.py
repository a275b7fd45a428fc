"""A fitted :class:`~sosdyn.lfd.model.pose.PoseCDSP` at run time: its chart's angular velocity
(:func:`body_velocity`), the speed limits (:func:`pose_speed_factor`), and standalone code: Python ``predict_pose(x, quat, goal=None)``
(:func:`pose_to_python`) or C++17 ``predict_pose(x, quat, v, omega, goal = nullptr)`` (:func:`pose_to_cpp`).

The module is the 6-D chart model's own export (:func:`~sosdyn.lfd.runtime.export_python.to_python`:
``predict(S)`` on s = (x, c r)) followed by the chart: r = log(R_g^T R) (scipy's ``Rotation``),
s = (x - x_g' + x_g, c r) for the goal pose (x_g', R_g'), and (v, omega) = (sdot_x,
R J_r(r) sdot_r / c) with :func:`body_velocity` (its source copied verbatim). It needs numpy
and scipy, never sosdyn. States within CHART_MARGIN of the cut locus raise ValueError. Speed limits
(``max_speed`` on |v|, ``max_angular_speed`` on |omega|, written into the code): (v, omega) scaled by
one factor, the speed limit's (:mod:`.states`) of the joint ratio of |v| / v_max and |omega| / w_max,
as :meth:`~sosdyn.lfd.model.pose.PoseCDSP.predictor`.

The C++ header is the chart model's :func:`~sosdyn.lfd.runtime.export_cpp.to_cpp` (namespace NS) and a
namespace NS_pose with the same chart in plain arithmetic (<cmath> only): quaternion product and
conjugate, log (r = 2 atan2(|v|, w) v / |v|, w >= 0) and the right Jacobian; it returns false for a
state that is not finite, a velocity that is not finite, or an orientation within CHART_MARGIN of the
cut locus.
"""
from __future__ import annotations

import inspect

import numpy as np

from ..data.pose import CHART_MARGIN
from .codegen import _flat, _literal
from .export_cpp import to_cpp
from .export_python import to_python
from .states import joint_ratio, saturation_factor, speed_ratio

SMALL_ANGLE = 1e-4               # below this |r| the right Jacobian's series is used


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


def pose_speed_factor(S, Sdot, rot_factor: float, max_speed, max_angular_speed) -> np.ndarray:
    """lambda (m, 1) of each chart state S (m, 6) (goal at r = 0) and velocity Sdot: the speed limit's
    factor (:mod:`.states`) of the joint ratio of |v| / v_max and |omega| / w_max
    (:func:`~.states.joint_ratio`), v = sdot_x, |omega| = |R J_r(r) rdot| = |J_r(r) rdot| with r = s_r / c,
    rdot = sdot_r / c. One positive factor on the whole 6-D velocity keeps the chart paths and the goal
    (docs/theory.md); |v| <= v_max and |omega| <= w_max."""
    w = body_velocity(S[:, 3:] / rot_factor, Sdot[:, 3:] / rot_factor)
    rho = joint_ratio([None if max_speed is None else speed_ratio(Sdot[:, :3], max_speed),
                       None if max_angular_speed is None else speed_ratio(w, max_angular_speed)])
    return np.broadcast_to(saturation_factor(rho), (len(S),))[:, None]




def pose_to_python(model, max_speed: float | None = None, max_angular_speed: float | None = None) -> str:
    """Source of the standalone pose module (module docstring)."""
    model._check_fitted()
    max_speed, max_angular_speed = model._limits(max_speed, max_angular_speed)
    return to_python(model.cdsp_) + f'''

# ---------------------------------------------------------------- the pose chart (PoseCDSP)
from scipy.spatial.transform import Rotation  # noqa: E402

GOAL_QUAT = np.array({_literal(model.goal_quat_)})   # w x y z
ROT_FACTOR = {float(model.rot_factor_)!r}            # s = (x, ROT_FACTOR * r)
CHART_LIMIT = {float(3.141592653589793 - CHART_MARGIN)!r}   # |r| below this (rad): away from the cut locus
SMALL_ANGLE = {SMALL_ANGLE!r}
POSE_MAX_SPEED = {max_speed!r}                  # None, or the largest |v| (units/s)
POSE_MAX_ANGULAR_SPEED = {max_angular_speed!r}  # None, or the largest |omega| (rad/s): (v, omega) scaled by one factor


{inspect.getsource(body_velocity)}

def predict_pose(x, quat, goal=None):
    """(v, omega): linear velocity (3,) and world angular velocity (3,) at the position x (3,) and the
    orientation quat (4,, w x y z), for the goal pose (x, y, z, qw, qx, qy, qz) or the model's."""
    x, quat = np.asarray(x, dtype=float), np.asarray(quat, dtype=float)
    if x.shape != (3,) or quat.shape != (4,) or not (np.isfinite(x).all() and np.isfinite(quat).all()):
        raise ValueError("x must be a finite 3-vector and quat a finite 4-vector (w x y z)")
    goal = np.concatenate([GOAL[:3], GOAL_QUAT]) if goal is None else np.asarray(goal, dtype=float)
    Rg = Rotation.from_quat(goal[3:], scalar_first=True)
    r = (Rg.inv() * Rotation.from_quat(quat, scalar_first=True)).as_rotvec()
    if np.linalg.norm(r) >= CHART_LIMIT:
        raise ValueError("the orientation is too near a half turn from the goal (the chart's cut locus)")
    sdot = predict(np.concatenate([x - goal[:3] + GOAL[:3], ROT_FACTOR * r]))
    v, omega = sdot[:3], (Rg * Rotation.from_rotvec(r)).apply(body_velocity(r, sdot[3:] / ROT_FACTOR)[0])
    scale = float(saturation_factor(joint_ratio([None if limit is None else speed_ratio(u, limit)
                                                 for limit, u in ((POSE_MAX_SPEED, v), (POSE_MAX_ANGULAR_SPEED, omega))])))
    return scale * v, scale * omega
'''


def _cpp_ratio(limit: float | None, vector: str) -> str:
    """A C++ expression: |vector| / limit (the speed limit's :func:`~.states.speed_ratio`), 0 without a limit."""
    return "0.0" if limit is None else f"{{NS}}::speed_ratio({vector}.data(), 3, {limit!r}, top, norm)"


def pose_to_cpp(model, namespace: str = "pose_model", max_speed: float | None = None,
                max_angular_speed: float | None = None) -> str:
    """Source of the header-only C++17 pose evaluator (module docstring)."""
    model._check_fitted()
    max_speed, max_angular_speed = model._limits(max_speed, max_angular_speed)
    limits = (("  double top, norm;   // scratch of speed_ratio\n" if (max_speed, max_angular_speed) != (None, None) else "")
              + f"  const double speed = {_cpp_ratio(max_speed, 'sdot')};\n"
              f"  const double turn = {_cpp_ratio(max_angular_speed, 'w_out')};\n"
              f"  const double scale = {{NS}}::joint_factor(speed, turn);   // |v| <= max_speed, |omega| <= max_angular_speed\n"
              ).replace("{NS}", namespace)
    return to_cpp(model.cdsp_, namespace) + f"""
namespace {namespace}_pose {{

constexpr std::array<double, 4> goal_quat = {{{_flat(model.goal_quat_)}}};   // w x y z
constexpr double rot_factor = {float(model.rot_factor_)!r};
constexpr double chart_limit = {float(3.141592653589793 - CHART_MARGIN)!r};
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
// model's): v = sdot_x, omega = R J_r(r) sdot_r / c, r = log(R_g^T R); false if not finite or near the cut locus.
inline bool predict_pose(const double* x, const double* quat, double* v, double* omega, const double* goal = nullptr) {{
  const double* gx = goal ? goal : {namespace}::goal.data();
  const double* gq = goal ? goal + 3 : goal_quat.data();
  double qn = 0.0, gn = 0.0;
  for (int i = 0; i < 4; ++i) {{ qn += quat[i] * quat[i]; gn += gq[i] * gq[i]; }}
  qn = std::sqrt(qn);
  gn = std::sqrt(gn);
  if (!(qn > 0.5 && qn < 1.5 && gn > 0.5 && gn < 1.5)) return false;
  const std::array<double, 4> q = {{quat[0] / qn, quat[1] / qn, quat[2] / qn, quat[3] / qn}};
  const std::array<double, 4> gc = {{gq[0] / gn, -gq[1] / gn, -gq[2] / gn, -gq[3] / gn}};
  const std::array<double, 3> r = qlog(qmul(gc.data(), q.data()));
  const double t = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (!(t < chart_limit)) return false;
  std::array<double, 6> s{{}}, sdot{{}};
  for (int i = 0; i < 3; ++i) {{
    s[i] = x[i] - gx[i] + {namespace}::goal[i];
    s[3 + i] = rot_factor * r[i];
  }}
  if (!{namespace}::predict(s.data(), sdot.data())) return false;
  const double a = t < small_angle ? 0.5 - t * t / 24.0 : (1.0 - std::cos(t)) / (t * t);
  const double b = t < small_angle ? 1.0 / 6.0 - t * t / 120.0 : (t - std::sin(t)) / (t * t * t);
  const std::array<double, 3> d = {{sdot[3] / rot_factor, sdot[4] / rot_factor, sdot[5] / rot_factor}};
  const std::array<double, 3> rxd = {{r[1] * d[2] - r[2] * d[1], r[2] * d[0] - r[0] * d[2], r[0] * d[1] - r[1] * d[0]}};
  const std::array<double, 3> rxrxd = {{r[1] * rxd[2] - r[2] * rxd[1], r[2] * rxd[0] - r[0] * rxd[2],
                                       r[0] * rxd[1] - r[1] * rxd[0]}};
  std::array<double, 4> wb = {{0.0, 0.0, 0.0, 0.0}};   // body angular velocity J_r(r) d, as a pure quaternion
  for (int i = 0; i < 3; ++i) wb[1 + i] = d[i] - a * rxd[i] + b * rxrxd[i];
  const std::array<double, 4> qc = {{q[0], -q[1], -q[2], -q[3]}};
  const std::array<double, 4> qw = qmul(q.data(), wb.data());
  const std::array<double, 4> w = qmul(qw.data(), qc.data());     // omega = R omega_b = q omega_b q*
  const std::array<double, 3> w_out = {{w[1], w[2], w[3]}};
{limits}  bool finite = true;
  for (int i = 0; i < 3; ++i) {{
    v[i] = scale * sdot[i];
    omega[i] = scale * w_out[i];
    finite = finite && std::isfinite(v[i]) && std::isfinite(omega[i]);
  }}
  return finite;
}}

}}  // namespace {namespace}_pose
"""

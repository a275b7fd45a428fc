"""A fitted :class:`~.pose.PoseCDSP` as a standalone Python module: ``predict_pose(x, quat, goal=None)``.

The module is the 6-D chart model's own export (:func:`~sosdyn.lfd.runtime.export.to_python`:
``predict(S)`` on s = (x, c r)) followed by the chart: r = log(R_g^T R) (scipy's ``Rotation``),
s = (x - x_g' + x_g, c r) for the goal pose (x_g', R_g'), and (v, omega) = (sdot_x,
R J_r(r) sdot_r / c) with :func:`~.pose.right_jacobian` (its source copied verbatim). It needs numpy
and scipy, never sosdyn. States within CHART_MARGIN of the cut locus raise ValueError.
"""
from __future__ import annotations

import inspect

from ..data.poses import CHART_MARGIN
from ..runtime.export import _literal, to_python
from .pose import SMALL_ANGLE, PoseCDSP, right_jacobian


def pose_to_python(model: PoseCDSP) -> str:
    """Source of the standalone pose module (module docstring)."""
    model._check_fitted()
    return to_python(model.cdsp_) + f'''

# ---------------------------------------------------------------- the pose chart (PoseCDSP)
from scipy.spatial.transform import Rotation  # noqa: E402

GOAL_QUAT = np.array({_literal(model.goal_quat_)})   # w x y z
ROT_FACTOR = {float(model.rot_factor_)!r}            # s = (x, ROT_FACTOR * r)
CHART_LIMIT = {float(3.141592653589793 - CHART_MARGIN)!r}   # |r| below this (rad): away from the cut locus
SMALL_ANGLE = {SMALL_ANGLE!r}


{inspect.getsource(right_jacobian)}

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
    return sdot[:3], (Rg * Rotation.from_rotvec(r)).apply(right_jacobian(r) @ (sdot[3:] / ROT_FACTOR))
'''

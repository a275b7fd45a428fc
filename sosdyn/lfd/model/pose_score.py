"""The reproduction table of a pose model (:meth:`~.pose.PoseCDSP.score`, ``sosdyn fit`` on pose files).

As :func:`~sosdyn.lfd.rollout.quality.reproduction_table` for positions, on the chart state s = (x, r):
explicit Euler (step ``dt_``) of the model's chart field from each demonstration's first pose for HORIZON x
its duration, then per demonstration

* ``mean_dev`` / ``max_dev``: distance from each demo position to the nearest reproduction position
  (:func:`~sosdyn.lfd.rollout.quality.deviation`, data units);
* ``mean_dev_deg`` / ``max_dev_deg``: geodesic angle from each demo orientation to the nearest
  reproduction orientation (:func:`~sosdyn.lfd.data.pose.angle_matrix`, degrees);
* ``arrival_s``: the first time within GOAL_FRACTION of the positions' diagonal (STILL_RELATIVE of their
  magnitude for positions that do not move) of the goal position and
  within ANGLE_TOL_DEG of the goal orientation (inf: not within the horizon);
* ``final_error`` (data units), ``final_angle_deg`` and ``at_goal`` (both within those radii).
"""
from __future__ import annotations

import numpy as np

from ..data.pose import angle_matrix, chart, from_chart
from ..rollout import euler_until_rest
from ..fit.pose import STILL_RELATIVE
from ..rollout.quality import GOAL_FRACTION, HORIZON, deviation

ANGLE_TOL_DEG = 1.0          # "at the goal orientation": within 1 deg
CHUNK = 1024                 # demo samples per block of the angle matrix


def nearest_angles(quat, path_quat) -> np.ndarray:
    """Geodesic angle (deg) from each row of ``quat`` to the nearest row of ``path_quat`` (in chunks)."""
    return np.concatenate([angle_matrix(quat[k:k + CHUNK], path_quat).min(axis=1)
                           for k in range(0, len(quat), CHUNK)])


def pose_reproduction_table(model, demos) -> list[dict]:
    """Rows of the module docstring for the fitted pose ``model`` and the pose ``demos``."""
    X = np.vstack([d.pos for d in demos])
    radius = max(GOAL_FRACTION * float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))),
                 STILL_RELATIVE * float(np.abs(X).max()))           # positions that do not move: round-off
    dt = model.dt_
    starts = np.array([np.concatenate([d.pos[0], chart(d.quat[0], model.goal_quat_)[0]]) for d in demos])
    steps = max(int(np.ceil(HORIZON * max(d.t[-1] - d.t[0] for d in demos) / dt)) + 2, 3)
    paths = euler_until_rest(lambda S: model.field(S, model.goal_pos_), starts, dt=dt, max_steps=steps,
                             vel_tol=np.finfo(float).tiny, window=1)
    rows = []
    for i, (d, full) in enumerate(zip(demos, paths)):
        duration = float(d.t[-1] - d.t[0])
        path = full[:int(np.ceil(HORIZON * duration / dt)) + 1]
        dev = deviation(d.pos, path[:, :3])
        angles = nearest_angles(d.quat, from_chart(path[:, 3:], model.goal_quat_))
        dist = np.linalg.norm(path[:, :3] - model.goal_pos_, axis=1)
        angle = np.rad2deg(np.linalg.norm(path[:, 3:], axis=1))
        inside = np.flatnonzero((dist <= radius) & (angle <= ANGLE_TOL_DEG))
        rows.append({"demo": i, "source": d.source, "mean_dev": float(dev.mean()), "max_dev": float(dev.max()),
                     "mean_dev_deg": float(angles.mean()), "max_dev_deg": float(angles.max()),
                     "arrival_s": float(inside[0] * dt) if inside.size else float("inf"), "duration_s": duration,
                     "final_error": float(dist[-1]), "final_angle_deg": float(angle[-1]),
                     "at_goal": bool(dist[-1] <= radius and angle[-1] <= ANGLE_TOL_DEG)})
    return rows

"""Pose reproduction metrics: geodesic angles, orientation DTW, final errors and arrival time.

* geodesic angle between unit quaternions (w x y z) p, q: theta = angle of (R_p^T R_q)
  (:meth:`scipy.spatial.transform.Rotation.magnitude`), in [0, pi]; q and -q give the same angle;
* orientation DTW: ``min_P sum_{(i, j) in P} theta(a_i, b_j)`` over monotone warping paths with
  steps (1,0), (0,1), (1,1) (the cumulative convention of :func:`~.metrics.dtwd`), in degrees;
  ``per_point`` = total / |P|;
* arrival: the first sample from which the trajectory stays within ``pos_tol`` of the goal
  position and ``ang_tol`` of the goal orientation (None if it never does).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.limits import check_bytes
from .metrics import DTWDistance, warping_path_length


def angles_deg(qa, qb) -> np.ndarray:
    """Geodesic angles (degrees) between the rows of qa and qb (same shape (T, 4), or one row)."""
    Ra = Rotation.from_quat(np.atleast_2d(qa), scalar_first=True)
    Rb = Rotation.from_quat(np.atleast_2d(qb), scalar_first=True)
    return np.rad2deg((Ra.inv() * Rb).magnitude())


def angle_matrix(qa, qb) -> np.ndarray:
    """(N, M) geodesic angles in degrees: theta = 2 arccos |<a_i, b_j>| (the rotation of R_a^T R_b)."""
    dots = np.clip(np.abs(np.asarray(qa, float) @ np.asarray(qb, float).T), 0.0, 1.0)
    return np.rad2deg(2.0 * np.arccos(dots))


def dtw_cost(C: np.ndarray) -> DTWDistance:
    """Cumulative DTW over the cost matrix C (N, M), by anti-diagonals (each a vector operation)."""
    N, M = C.shape
    check_bytes(8.0 * (N + 1) * (M + 1), f"DTW of {N} x {M} points (the cost matrix)", "subsample the curves")
    D = np.full((N + 1, M + 1), np.inf)
    D[0, 0] = 0.0
    for k in range(2, N + M + 1):
        i = np.arange(max(1, k - M), min(N, k - 1) + 1)
        j = k - i
        D[i, j] = C[i - 1, j - 1] + np.minimum(np.minimum(D[i - 1, j - 1], D[i - 1, j]), D[i, j - 1])
    length = warping_path_length(D)
    return DTWDistance(float(D[N, M]), float(D[N, M]) / length, (N, M), length)


def orientation_dtw(qa, qb) -> DTWDistance:
    """Orientation DTW (module docstring) between two quaternion curves (T, 4)."""
    return dtw_cost(angle_matrix(qa, qb))


def arrival_index(pos, quat, goal_pos, goal_quat, pos_tol: float, ang_tol_deg: float) -> int | None:
    """First index from which every sample is within pos_tol and ang_tol_deg of the goal pose."""
    inside = (np.linalg.norm(np.asarray(pos) - goal_pos, axis=1) <= pos_tol) & \
             (angles_deg(quat, goal_quat) <= ang_tol_deg)
    if not inside[-1]:
        return None
    outside = np.flatnonzero(~inside)
    return int(outside[-1] + 1) if outside.size else 0


__all__ = ["angle_matrix", "angles_deg", "arrival_index", "dtw_cost", "orientation_dtw"]

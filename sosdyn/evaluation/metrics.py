"""Accuracy metrics for reproductions of demonstrations: DTWD, SEA, velocity and goal errors.

Units: positions in the data's length unit L (mm for LASA), time in s. Curves are given as
arrays (T, n) or as objects with a ``pos`` attribute (``Trajectory``, ``Demonstration``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sosdyn.errors import InputError, SosdynError
from sosdyn.limits import check_bytes
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations, resample_in_time


def curve(x, what: str) -> np.ndarray:
    """Positions (T, n) of an array or of an object with ``pos``, as a writable float copy,
    checked finite and non-empty (InputError naming ``what`` and the first bad sample)."""
    try:
        arr = np.array(getattr(x, "pos", x), dtype=float)  # a writable copy (the C DTW needs one)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be an array (T, n) or have a .pos array ({exc}).") from exc
    if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise InputError(f"{what} has shape {arr.shape}; expected (T, n) with T, n >= 1.")
    if not np.all(np.isfinite(arr)):
        first = np.flatnonzero(~np.isfinite(arr).all(axis=1))[0]
        raise InputError(f"{what} contains NaN or inf (first at sample {first}).")
    return arr


def _pair(a, b) -> tuple[np.ndarray, np.ndarray]:
    A, B = curve(a, "first curve"), curve(b, "second curve")
    if A.shape[1] != B.shape[1]:
        raise InputError(f"The curves have dimensions {A.shape[1]} and {B.shape[1]}; they must match.")
    return A, B


def as_demonstrations(demos) -> Demonstrations:
    """``demos`` itself if it is a non-empty Demonstrations; one Demonstration is wrapped."""
    if isinstance(demos, Demonstration):
        return Demonstrations([demos])
    if not isinstance(demos, Demonstrations) or not len(demos):
        raise InputError(f"Expected a non-empty Demonstrations (or one Demonstration), got {demos!r}.")
    return demos


# ---------------------------------------------------------------- dynamic time warping


@dataclass(frozen=True)
class DTWDistance:
    """DTW distance (L): ``total`` cost of the best warping path, ``per_point`` = total /
    ``path_length``, ``n_points`` = (len a, len b)."""

    total: float
    per_point: float
    n_points: tuple[int, int]
    path_length: int


def warping_path_length(D: np.ndarray) -> int:
    """Number of pairs on the optimal warping path, traced back through the cumulative cost
    matrix D (N+1, M+1) from (N, M) to (1, 1), preferring diagonal, then vertical steps."""
    item = D.item  # plain floats: much faster than numpy scalar indexing in this loop
    i, j, length = D.shape[0] - 1, D.shape[1] - 1, 1
    while i > 1 or j > 1:
        diagonal, up, left = item(i - 1, j - 1), item(i - 1, j), item(i, j - 1)
        if diagonal <= up and diagonal <= left:
            i, j = i - 1, j - 1
        elif up <= left:
            i -= 1
        else:
            j -= 1
        length += 1
    return length


def dtwd(a, b) -> DTWDistance:
    """Dynamic time warping distance with Euclidean point cost.

    ``total = min_P sum_{(i, j) in P} ||a_i - b_j||`` over monotone warping paths P from
    (0, 0) to (N-1, M-1) with steps (1,0), (0,1), (1,1): the cumulative (not root-of-squares)
    sum, the convention of ds-opt and of the CDSP authors. ``per_point = total / |P|``.
    Uses the C implementation of dtaidistance (about 10 ms for 1000 x 1000 points); the
    (N+1) x (M+1) cost matrix is checked against ``max_bytes`` first.
    """
    A, B = _pair(a, b)
    check_bytes(8.0 * (len(A) + 1) * (len(B) + 1), f"DTW of {len(A)} x {len(B)} points (the cost matrix)",
                "subsample the curves")
    try:   # lazy: dtaidistance is an optional dependency (the "eval" extra); say how to get it
        from dtaidistance import dtw
    except ImportError as exc:
        raise SosdynError("dtwd needs dtaidistance: pip install 'dtaidistance>=2.3.12'.") from exc
    if not dtw.try_import_c():
        raise SosdynError("dtaidistance is installed without its C extension; reinstall a wheel "
                          "that ships it: pip install --force-reinstall 'dtaidistance>=2.3.12'.")
    # inner_dist="euclidean" accumulates ||a_i - b_j|| (the default accumulates squares and
    # returns the square root); warping_path(use_c=True) ignores inner_dist, so the path is
    # read back from the cumulative-cost matrix instead.
    total, D = dtw.warping_paths_fast(A, B, use_ndim=True, inner_dist="euclidean")
    length = warping_path_length(D)
    return DTWDistance(float(total), float(total) / length, (len(A), len(B)), length)


# ---------------------------------------------------------------- swept error area


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _triangle_area(a, b, c):
    """Area of triangles (a, b, c) in any dimension: 0.5 sqrt(|u|^2 |v|^2 - (u.v)^2)."""
    u, v = b - a, c - a
    gram = np.sum(u * u, -1) * np.sum(v * v, -1) - np.sum(u * v, -1) ** 2
    return 0.5 * np.sqrt(np.maximum(gram, 0.0))


def _crossing(p, r, q, w):
    """Where segments p + s r and q + u w cross inside both (0 < s, u < 1): (mask, point)."""
    denom = _cross(r, w)
    safe = np.where(denom == 0, 1.0, denom)
    s, u = _cross(q - p, w) / safe, _cross(q - p, r) / safe
    mask = (denom != 0) & (s > 0) & (s < 1) & (u > 0) & (u < 1)
    return mask, p + s[:, None] * r


def quadrilateral_areas(p0, p1, p2, p3) -> np.ndarray:
    """Areas of the quadrilaterals p0 -> p1 -> p2 -> p3 (arrays (K, n)), shape (K,).

    2-D: the shoelace formula, except for crossed (bow-tie) quadrilaterals, which are split at
    the crossing X of two opposite edges into two triangles whose areas are added (edges p0p1
    and p2p3: (p0, X, p3) + (X, p1, p2); edges p1p2 and p3p0: (p0, p1, X) + (X, p2, p3)).
    n > 2: the smaller of the two diagonal splits (p0p2 or p1p3) into two triangles; exact for
    planar simple quadrilaterals, an upper bound otherwise.
    """
    if p0.shape[1] != 2:
        split02 = _triangle_area(p0, p1, p2) + _triangle_area(p0, p2, p3)
        split13 = _triangle_area(p1, p2, p3) + _triangle_area(p1, p3, p0)
        return np.minimum(split02, split13)
    area = 0.5 * np.abs(_cross(p0, p1) + _cross(p1, p2) + _cross(p2, p3) + _cross(p3, p0))
    cross_a, xa = _crossing(p0, p1 - p0, p2, p3 - p2)
    cross_b, xb = _crossing(p1, p2 - p1, p3, p0 - p3)
    area = np.where(cross_a, _triangle_area(p0, xa, p3) + _triangle_area(xa, p1, p2), area)
    return np.where(cross_b, _triangle_area(p0, p1, xb) + _triangle_area(xb, p2, p3), area)


def resample(reproduction, n_samples: int) -> np.ndarray:
    """``n_samples`` positions of a reproduction, equidistant in time (linear interpolation).

    Uses ``reproduction.t`` when present, otherwise assumes uniform sampling.
    """
    X = curve(reproduction, "reproduction")
    t = np.asarray(getattr(reproduction, "t", np.arange(len(X))), dtype=float)
    if len(X) < 2 or t.shape != (len(X),) or np.any(np.diff(t) <= 0):
        raise InputError(f"The reproduction needs >= 2 samples with increasing times, got {len(X)} samples.")
    return resample_in_time(t, X, n_samples)


def sea(reproduction, demo) -> float:
    """Swept error area (Khansari-Zadeh & Billard 2014, eq. 14), in L^2.

    ``SEA = sum_{t=0}^{T-2} A(xh_t, xh_{t+1}, x_{t+1}, x_t)``: the demo ``x`` (T samples) and
    the reproduction resampled equidistantly in time to T samples ``xh``; A is the area of
    the quadrilateral (see :func:`quadrilateral_areas`). The caller passes a reproduction over
    the same duration as the demo (e.g. :func:`evaluate_reproductions`), so SEA penalises both
    spatial and temporal mismatch.
    """
    X = curve(demo, "demo")
    if len(X) < 2:
        raise InputError("The demo needs at least 2 samples for SEA.")
    Xh = resample(reproduction, len(X))
    if Xh.shape[1] != X.shape[1]:
        raise InputError(f"Reproduction dimension {Xh.shape[1]} differs from the demo's {X.shape[1]}.")
    return float(np.sum(quadrilateral_areas(Xh[:-1], Xh[1:], X[1:], X[:-1])))


# ---------------------------------------------------------------- velocity field errors


def _velocity_pairs(model_or_predict, demos) -> tuple[np.ndarray, np.ndarray]:
    """(predicted, demonstrated) velocities at all demo samples, each (sum T, n)."""
    predict = getattr(model_or_predict, "predict", model_or_predict)
    if not callable(predict):
        raise InputError("Pass a model with .predict(X) or a function X (m, n) -> Xdot (m, n).")
    X, Xdot = as_demonstrations(demos).stacked()
    P = np.asarray(predict(X), dtype=float)
    if P.shape != Xdot.shape:
        raise InputError(f"predict returned shape {P.shape} for X of shape {X.shape}; expected {Xdot.shape}.")
    if not np.all(np.isfinite(P)):
        raise InputError("predict returned NaN or inf; check the model.")
    return P, Xdot


def velocity_rmse(model_or_predict, demos) -> float:
    """``sqrt(mean_k ||xdot_hat(x_k) - xdot_k||^2)`` over all demo samples, in L/s."""
    P, V = _velocity_pairs(model_or_predict, demos)
    return float(np.sqrt(np.mean(np.sum((P - V) ** 2, axis=1))))


def edot(model_or_predict, demos, *, min_speed: float | None = None) -> float:
    """Mean directional error ``mean_k (1 - cos angle(xdot_hat_k, xdot_k))``, in [0, 2].

    Samples where either speed is below ``min_speed`` (L/s; default 1 % of the median demo
    speed) are skipped: their direction is undefined.
    """
    P, V = _velocity_pairs(model_or_predict, demos)
    sp, sv = np.linalg.norm(P, axis=1), np.linalg.norm(V, axis=1)
    floor = 0.01 * float(np.median(sv)) if min_speed is None else float(min_speed)
    keep = (sp > floor) & (sv > floor)
    if not keep.any():
        raise InputError(f"No sample has both speeds above min_speed = {floor:g}; lower min_speed.")
    return float(np.mean(1.0 - np.sum(P[keep] * V[keep], axis=1) / (sp[keep] * sv[keep])))


def goal_error(traj, goal) -> float:
    """``||x(T) - goal||``: distance of the last position to the goal, in L."""
    X = curve(traj, "trajectory")
    g = np.asarray(goal, dtype=float)
    if g.shape != (X.shape[1],):
        raise InputError(f"goal has shape {g.shape}; expected ({X.shape[1]},).")
    return float(np.linalg.norm(X[-1] - g))

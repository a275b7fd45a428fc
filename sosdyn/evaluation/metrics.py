"""Accuracy metrics for reproductions of demonstrations.

Units: positions in the data's length unit L (mm for LASA), time in s. Curves are given as
arrays (T, n) or as objects with a ``pos`` attribute (``Trajectory``, ``Demonstration``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sosdyn.errors import InputError, SolverError, SosdynError
from sosdyn.lfd.data import Demonstration, Demonstrations


def _curve(x, what: str) -> np.ndarray:
    """Positions (T, n) of an array or of an object with ``pos``, checked finite and non-empty."""
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
    A, B = _curve(a, "first curve"), _curve(b, "second curve")
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


def _path_length(D: np.ndarray) -> int:
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
    Uses the C implementation of dtaidistance (about 10 ms for 1000 x 1000 points).
    """
    A, B = _pair(a, b)
    try:
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
    length = _path_length(D)
    return DTWDistance(float(total), float(total) / length, (len(A), len(B)), length)


def dtwd_reference(a, b) -> DTWDistance:
    """Pure numpy/Python O(N M) version of :func:`dtwd` (slow; for tests and cross-checks).

    ``D[i, j] = ||a_i - b_j|| + min(D[i-1, j-1], D[i-1, j], D[i, j-1])`` with ``D[0, 0] = 0``
    and ``inf`` on the rest of row and column 0 (1-based indices into a and b).
    """
    A, B = _pair(a, b)
    cost = np.linalg.norm(A[:, None, :] - B[None, :, :], axis=2)
    D = np.full((len(A) + 1, len(B) + 1), np.inf)
    D[0, 0] = 0.0
    for i in range(1, len(A) + 1):
        for j in range(1, len(B) + 1):
            D[i, j] = cost[i - 1, j - 1] + min(D[i - 1, j - 1], D[i - 1, j], D[i, j - 1])
    length = _path_length(D)
    return DTWDistance(float(D[-1, -1]), float(D[-1, -1]) / length, (len(A), len(B)), length)


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
    X = _curve(reproduction, "reproduction")
    t = np.asarray(getattr(reproduction, "t", np.arange(len(X))), dtype=float)
    if len(X) < 2 or t.shape != (len(X),) or np.any(np.diff(t) <= 0):
        raise InputError(f"The reproduction needs >= 2 samples with increasing times, got {len(X)} samples.")
    query = np.linspace(t[0], t[-1], n_samples)
    return np.column_stack([np.interp(query, t, X[:, k]) for k in range(X.shape[1])])


def sea(reproduction, demo) -> float:
    """Swept error area (Khansari-Zadeh & Billard 2014, eq. 14), in L^2.

    ``SEA = sum_{t=0}^{T-2} A(xh_t, xh_{t+1}, x_{t+1}, x_t)``: the demo ``x`` (T samples) and
    the reproduction resampled equidistantly in time to T samples ``xh``; A is the area of
    the quadrilateral (see :func:`quadrilateral_areas`). The caller passes a reproduction over
    the same duration as the demo (e.g. :func:`evaluate_reproductions`), so SEA penalises both
    spatial and temporal mismatch.
    """
    X = _curve(demo, "demo")
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
    X = _curve(traj, "trajectory")
    g = np.asarray(goal, dtype=float)
    if g.shape != (X.shape[1],):
        raise InputError(f"goal has shape {g.shape}; expected ({X.shape[1]},).")
    return float(np.linalg.norm(X[-1] - g))


# ---------------------------------------------------------------- rollouts of models


def rollout_function(model):
    """``model.rollout`` if present, else ``model`` itself: called as ``f(x0, duration, dt=...)``."""
    fn = getattr(model, "rollout", model)
    if not callable(fn):
        raise InputError("Pass a model with .rollout(x0, duration, dt=...) or such a function.")
    return fn


def summarize(values: dict[str, list]) -> tuple[dict[str, float], dict[str, float]]:
    """Mean and (population, ddof = 0) standard deviation of each list of numbers; both are inf
    when a list holds inf (a failed rollout)."""
    finite = {k: bool(np.all(np.isfinite(v))) for k, v in values.items()}
    return ({k: float(np.mean(v)) if finite[k] else np.inf for k, v in values.items()},
            {k: float(np.std(v)) if finite[k] else np.inf for k, v in values.items()})


@dataclass
class GridConvergence:
    """Result of :func:`grid_convergence`: ``fraction`` converged of ``n_starts``; each failure is
    a dict with ``x0``, ``final_error`` (L, inf if the rollout failed) and ``reason``."""

    fraction: float
    n_starts: int
    tol: float
    failures: list[dict]


def grid_starts(demos, n_grid: int = 10, seed: int = 0) -> np.ndarray:
    """Start points over the data's bounding box scaled by 2 about its centre.

    n <= 2: a full grid with ``n_grid`` points per axis; n > 2: ``n_grid**2`` uniform random
    points (``seed``). Flat axes get the half-width of the widest axis (1 if all are flat).
    """
    X, _ = as_demonstrations(demos).stacked()
    if isinstance(n_grid, bool) or not isinstance(n_grid, (int, np.integer)) or n_grid < 2:
        raise InputError(f"n_grid must be an integer >= 2, got {n_grid!r}.")
    lo, hi = X.min(axis=0), X.max(axis=0)
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    half = np.where(half > 0, half, max(half.max(), 1.0))
    lo, hi = centre - 2 * half, centre + 2 * half
    if X.shape[1] <= 2:
        axes = np.meshgrid(*[np.linspace(a, b, n_grid) for a, b in zip(lo, hi)], indexing="ij")
        return np.column_stack([a.ravel() for a in axes])
    return np.random.default_rng(seed).uniform(lo, hi, size=(n_grid**2, X.shape[1]))


def grid_convergence(model_rollout_fn, demos, n_grid: int = 10, horizon: float | None = None,
                     tol_mm: float = 1.0, *, dt: float | None = None, seed: int = 0) -> GridConvergence:
    """Fraction of rollouts from :func:`grid_starts` that end within ``tol_mm`` (L) of their goal.

    Each start is rolled out for ``horizon`` s (default 5 x the longest demo), sampled every
    ``dt`` (default horizon / 500), at the model's training goal; converged means
    ``||x(horizon) - goal|| <= tol_mm``. A rollout that raises SolverError counts as a failure.
    """
    demos = as_demonstrations(demos)
    fn = rollout_function(model_rollout_fn)
    horizon = 5.0 * max(d.duration for d in demos) if horizon is None else float(horizon)
    dt = horizon / 500 if dt is None else float(dt)
    starts = grid_starts(demos, n_grid, seed)
    failures = []
    for x0 in starts:
        try:
            traj = fn(x0, horizon, dt=dt)
        except SolverError as exc:
            failures.append({"x0": x0, "final_error": np.inf, "reason": str(exc)})
            continue
        error = goal_error(traj, traj.goal_history[-1])
        if not error <= tol_mm:
            failures.append({"x0": x0, "final_error": error, "reason": f"ends {error:.3g} from the goal"})
    return GridConvergence(1.0 - len(failures) / len(starts), len(starts), float(tol_mm), failures)


_BATCH_METHODS = ("LSODA", "BDF", "Radau")


def _integrate_batch(field, X0: np.ndarray, horizon: float, goal: np.ndarray, *, method: str,
                     rtol: float, atol: float, escape: float = np.inf) -> np.ndarray:
    """Final states (m, n) of ``xdot = field(x, goal)`` from all rows of ``X0`` at once.

    The starts are stacked into one ODE ``y = X.ravel()`` (start-major, so its Jacobian is
    block diagonal with n x n blocks). LSODA is told the band (``lband = uband = n - 1``), so
    a finite-difference Jacobian costs 2n - 1 field calls, not m n; BDF/Radau get the block
    sparsity pattern. LSODA's error test uses the weighted max-norm, so every start is held
    to ``rtol``/``atol`` as in a rollout of its own. Starts farther than ``escape`` from the
    goal are frozen there (their derivative set to 0): they have diverged, and integrating
    their exponential growth would only shrink everybody's steps. Raises SolverError on failure.
    """
    from scipy.integrate import solve_ivp

    m, n = X0.shape

    def rhs(_t, y):
        X = y.reshape(m, n)
        V = np.asarray(field(X, goal), dtype=float)
        if V.shape != X.shape:
            raise InputError(f"The field returned shape {V.shape} for X of shape {X.shape}.")
        if not np.all(np.isfinite(V)):
            raise SolverError("The field returned NaN/inf.", status="solver_error")
        if np.isfinite(escape):
            V[np.linalg.norm(X - goal, axis=1) > escape] = 0.0
        return V.ravel()

    options = {}
    if method == "LSODA":
        options = {"lband": n - 1, "uband": n - 1}
    else:
        from scipy.sparse import block_diag
        options = {"jac_sparsity": block_diag([np.ones((n, n))] * m, format="csc")}
    with np.errstate(over="ignore", invalid="ignore"):
        sol = solve_ivp(rhs, (0.0, horizon), X0.ravel(), method=method, t_eval=[horizon],
                        rtol=rtol, atol=atol, **options)
    if not sol.success or sol.y.shape[1] != 1 or not np.all(np.isfinite(sol.y)):
        raise SolverError(f"Integration failed: {sol.message}", status="solver_error")
    return sol.y[:, -1].reshape(m, n)


def final_states(field, starts, horizon: float, goal, *, method: str = "LSODA", rtol: float = 1e-6,
                 atol: float = 1e-8, escape: float = np.inf) -> tuple[np.ndarray, list[str | None]]:
    """``x(horizon)`` of ``xdot = field(x, goal)`` from every row of ``starts`` (m, n), batched.

    All starts are integrated as one ODE (:func:`_integrate_batch`); if that fails (a start
    diverges, the field returns NaN), the batch is split in halves recursively, so only the
    failing starts are lost. Returns the final states (inf rows for failures) and, per
    start, None or the failure reason. ``escape``: see :func:`_integrate_batch`; a start
    frozen there is reported with reason "diverged".
    """
    X0 = np.atleast_2d(np.asarray(starts, dtype=float))
    goal = np.asarray(goal, dtype=float)
    if method not in _BATCH_METHODS:
        raise InputError(f"method must be one of {_BATCH_METHODS}, got {method!r}.")
    out = np.full(X0.shape, np.inf)
    reasons: list[str | None] = [None] * len(X0)

    def solve(idx):
        try:
            out[idx] = _integrate_batch(field, X0[idx], float(horizon), goal, method=method,
                                        rtol=rtol, atol=atol, escape=escape)
            for i in idx:
                if np.linalg.norm(out[i] - goal) > escape:
                    reasons[i] = f"diverged: left the ball of radius {escape:.3g} about the goal"
        except SolverError as exc:
            if len(idx) == 1:
                reasons[idx[0]] = str(exc)
                return
            half = len(idx) // 2
            solve(idx[:half])
            solve(idx[half:])

    if len(X0):
        solve(np.arange(len(X0)))
    return out, reasons


def grid_convergence_batched(model, demos, n_grid: int = 10, horizon: float | None = None,
                             tol_mm: float = 1.0, *, goal=None, seed: int = 0, method: str = "LSODA",
                             rtol: float = 1e-6, atol: float = 1e-8,
                             escape_factor: float = 100.0) -> GridConvergence:
    """:func:`grid_convergence` for an autonomous model, all starts integrated at once.

    ``model`` has ``field(X (m, n), goal) -> Xdot (m, n)`` (the field functions of CDSP, GMR
    and CLF-DM accept many rows) and ``goal_``; or pass the field callable itself and ``goal``
    (default: the demos' goal). Same starts, horizon (default 5 x the longest demo), goal and
    criterion ``||x(horizon) - goal|| <= tol_mm`` as :func:`grid_convergence`, with the
    integrator's tolerances of a single rollout; about one rollout's cost instead of
    ``n_grid**2`` (see :func:`final_states`). A start whose integration fails counts as a
    failure with ``final_error`` inf; one that gets farther than ``escape_factor`` x the
    diagonal of the data's bounding box from the goal is stopped there and counts as a
    failure (diverged) with its distance at that moment.
    """
    demos = as_demonstrations(demos)
    field = getattr(model, "field", model)
    if not callable(field):
        raise InputError("Pass a model with .field(X, goal) or such a function.")
    if goal is None:
        goal = getattr(model, "goal_", None)
    goal = np.asarray(demos.goal if goal is None else goal, dtype=float)
    if goal.shape != (demos.dim,):
        raise InputError(f"goal has shape {goal.shape}; expected ({demos.dim},).")
    horizon = 5.0 * max(d.duration for d in demos) if horizon is None else float(horizon)
    if not horizon > 0:
        raise InputError(f"horizon must be > 0, got {horizon!r}.")
    starts = grid_starts(demos, n_grid, seed)
    X, _ = demos.stacked()
    escape = escape_factor * max(float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))), tol_mm)
    final, reasons = final_states(field, starts, horizon, goal, method=method, rtol=rtol, atol=atol,
                                  escape=escape)
    errors = np.linalg.norm(final - goal, axis=1)
    failures = []
    for x0, error, reason in zip(starts, errors, reasons):
        if reason is not None and reason.startswith("diverged"):
            failures.append({"x0": x0, "final_error": float(error), "reason": reason})
        elif reason is not None:
            failures.append({"x0": x0, "final_error": np.inf, "reason": reason})
        elif not error <= tol_mm:
            failures.append({"x0": x0, "final_error": float(error),
                             "reason": f"ends {error:.3g} from the goal"})
    return GridConvergence(1.0 - len(failures) / len(starts), len(starts), float(tol_mm), failures)


def evaluate_reproductions(model, demos) -> dict:
    """Reproduce each demo from its first point and score it.

    Each rollout lasts the demo's own duration with dt = its mean step (so it has the demo's
    sample count), at the model's training goal (``goal=None``). Returns per-demo lists
    ``sea`` (L^2), ``dtwd`` and ``dtwd_per_point`` (L), ``goal_error`` (L, to the goal in
    effect at the end), ``trajectories``, and their ``mean`` / ``std`` (ddof = 0).
    """
    demos = as_demonstrations(demos)
    fn = rollout_function(model)
    scores = {"sea": [], "dtwd": [], "dtwd_per_point": [], "goal_error": []}
    trajectories = []
    for demo in demos:
        traj = fn(demo.pos[0], demo.duration, dt=demo.duration / (len(demo.t) - 1))
        distance = dtwd(traj, demo)
        scores["sea"].append(sea(traj, demo))
        scores["dtwd"].append(distance.total)
        scores["dtwd_per_point"].append(distance.per_point)
        scores["goal_error"].append(goal_error(traj, traj.goal_history[-1]))
        trajectories.append(traj)
    mean, std = summarize(scores)
    return {**scores, "trajectories": trajectories, "mean": mean, "std": std}

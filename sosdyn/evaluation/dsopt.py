"""The LASA evaluation protocol of LPV-DS (Figueroa & Billard, CoRL 2018), as array functions.

The protocol, as run by ``evaluation-scripts/evaluate_LPVDS_PCGMM.m`` and ``evaluate_SEDS.m``
of the public repository nbfigueroa/ds-opt (with ``lpv-opt/CLFDM_lib/Simulation.m`` and
``thirdparty/dtwd/.../dtw.m``):

1. Per shape, train on demonstrations 1-4 and test on 5-7 (1-based), each keeping every 2nd
   sample (``pos(:, 1:2:end)``, ``vel(:, 1:2:end)``): 500 of LASA's 1000 points.
2. Reproduce with explicit Euler, ``x_{i+1} = x_i + dt f(x_i)``, dt = 0.01 s, from the 20th
   kept point of each demonstration, all starts integrated together; stop at the first step i
   (>= 4) at which every velocity component of every start was below 0.1 (L/s) in absolute
   value at steps i-3..i, or at step i = 3000 - 1 (``Simulation.m``: ``i > i_max - 2``). The
   reproduction is x_1..x_i (the last Euler update is dropped), so at most 2999 points.
3. DTWD = cumulative Euclidean dynamic time warping between the reproduction and the whole
   500-point demonstration (no window; steps (1,0), (0,1), (1,1)); mean over the 3 test
   demonstrations, then over the 26 single-pattern shapes (all LASA shapes but
   Multi_Models_1-4).

Published test means over the 26 shapes: SEDS 3954, LPV-DS (EM GMM) 1990, LPV-DS PC-GMM
1749 / 1751; copying the nearest training demonstration (:func:`nearest_demo_score`) scores
660. Units: the data's length unit L (mm for LASA) and seconds. ds-opt fixes the attractor
at the origin (where LASA demonstrations end); here a fitted model keeps its own goal (for
CDSP the mean last kept point, within 0.05 mm of the origin on LASA).
"""

from __future__ import annotations

import csv
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.spatial.distance import cdist

from sosdyn.errors import InputError, SolverError
from sosdyn.lfd.data import Demonstration, Demonstrations
from sosdyn.limits import check_bytes, check_count

TRAIN_DEMOS = (0, 1, 2, 3)          # 0-based indices of the training demonstrations (1-4)
TEST_DEMOS = (4, 5, 6)              # and of the test demonstrations (5-7)
SAMPLE_STEP = 2                     # keep every 2nd sample
START_INDEX = 19                    # reproductions start at the 20th kept point
DT, MAX_STEPS, VEL_TOL, WINDOW = 0.01, 3000, 0.1, 4

# The shape list of ds-opt's evaluation (``load_LASA_dataset_shape_DS.m``, models 1-26):
# every LASA shape except the four Multi_Models, sorted as ``sosdyn.lasa_names()`` sorts them.
SINGLE_PATTERN_SHAPES = (
    "Angle", "BendedLine", "CShape", "DoubleBendedLine", "GShape", "JShape", "JShape_2",
    "Khamesh", "LShape", "Leaf_1", "Leaf_2", "Line", "NShape", "PShape", "RShape", "Saeghe",
    "Sharpc", "Sine", "Snake", "Spoon", "Sshape", "Trapezoid", "WShape", "Worm", "Zshape", "heee",
)


def _positions(x, what: str) -> np.ndarray:
    """Positions (T, n) of an array or of an object with ``pos``, checked finite and non-empty."""
    try:
        arr = np.asarray(getattr(x, "pos", x), dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be an array (T, n) or have a .pos array ({exc}).") from exc
    if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise InputError(f"{what} has shape {arr.shape}; expected (T, n) with T, n >= 1.")
    if not np.all(np.isfinite(arr)):
        first = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InputError(f"{what} contains NaN or inf (first at sample {first}); pass finite values.")
    return arr


# ---------------------------------------------------------------- train / test split


def split(demos) -> tuple[Demonstrations, Demonstrations]:
    """Protocol step 1: (train, test) = demonstrations 1-4 and 5-7, every 2nd sample kept.

    Sample k of a kept demonstration is sample 2k of the original (k = 0, 1, ...; the last
    original sample is dropped when T is even, as MATLAB's ``1:2:end`` drops it), with its
    own time stamp and its recorded velocity: ``vel`` stays the derivative at ``t``, since
    subsampling changes which instants are kept, not what was measured at them.
    """
    items = list(demos)
    needed = max(TEST_DEMOS) + 1
    if len(items) < needed:
        raise InputError(
            f"The protocol needs {needed} demonstrations (train 1-4, test 5-7), got {len(items)}. "
            "Try: a LASA shape (sosdyn.load_lasa), which has 7.")
    for i, d in enumerate(items):
        if not isinstance(d, Demonstration):
            raise InputError(f"Item {i} is a {type(d).__name__}, not a Demonstration.")
    name, units = getattr(demos, "name", ""), getattr(demos, "units", "")

    def keep(indices):
        return Demonstrations(
            [Demonstration(d.t[::SAMPLE_STEP], d.pos[::SAMPLE_STEP], d.vel[::SAMPLE_STEP], d.source)
             for d in (items[i] for i in indices)], name, units)

    return keep(TRAIN_DEMOS), keep(TEST_DEMOS)


def start_points(demos) -> np.ndarray:
    """The reproductions' starts: the 20th kept point of each demonstration, (m, n)."""
    curves = [_positions(d, f"demonstration {i}") for i, d in enumerate(demos)]
    short = [i for i, c in enumerate(curves) if len(c) <= START_INDEX]
    if short:
        raise InputError(f"Demonstration {short[0]} has {len(curves[short[0]])} samples; the protocol "
                         f"starts at sample {START_INDEX + 1}. Try: longer demonstrations.")
    return np.array([c[START_INDEX] for c in curves])


# ---------------------------------------------------------------- reproduction


def euler_reproduce(field: Callable[[np.ndarray], np.ndarray], starts, dt: float = DT,
                    max_steps: int = MAX_STEPS, vel_tol: float = VEL_TOL,
                    window: int = WINDOW) -> list[np.ndarray]:
    """Protocol step 2: explicit-Euler reproductions from all rows of ``starts`` (m, n) at once.

    ``v_i = field(X_i)`` (one call for all m starts), ``X_{i+1} = X_i + dt v_i``, i = 1, 2, ...
    Stops at the first i >= ``window`` with ``|v_j[s, c]| < vel_tol`` for every start s,
    component c and j = i-window+1..i, or at i = ``max_steps`` - 1 (``Simulation.m`` stops at
    ``i > i_max - 2``). Returns m arrays (i, n): x_1..x_i of each start (the last update,
    X_{i+1}, is dropped as in ``Simulation.m``), all of the same length i.

    Raises InputError if ``field`` returns another shape, SolverError if a state or a velocity
    becomes NaN/inf (the reproduction diverged).
    """
    X = np.array(starts, dtype=float, ndmin=2)
    if X.ndim != 2 or not np.all(np.isfinite(X)):
        raise InputError(f"starts must be a finite array (m, n), got shape {X.shape}.")
    for name, value, lo in (("max_steps", max_steps, 2), ("window", window, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise InputError(f"{name} must be an integer >= {lo}, got {value!r}.")
    for name, value in (("dt", dt), ("vel_tol", vel_tol)):
        if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive number, got {value!r}.")
    m, n = X.shape
    check_count(max_steps * m, "max_rollout_steps", f"An Euler reproduction of {m} starts x max_steps",
                "lower max_steps")
    check_bytes(8.0 * max_steps * m * n, "The Euler reproduction's trajectory array", "lower max_steps")
    out = np.empty((max(max_steps - 1, window), m, n))
    quiet, i = 0, 0                             # steps in a row with every |v| < vel_tol; step
    while True:
        i += 1
        if not np.all(np.isfinite(X)):
            bad = int(np.flatnonzero(~np.isfinite(X).all(axis=1))[0])
            raise SolverError(f"The reproduction from start {bad} diverged: its state is NaN/inf at "
                              f"step {i}.", hint="check the model's stability, or lower dt.")
        out[i - 1] = X
        V = np.asarray(field(X), dtype=float)
        if V.shape != X.shape:
            raise InputError(f"The field returned shape {V.shape} for X of shape {X.shape}; "
                             "expected the same shape.")
        if not np.all(np.isfinite(V)):
            bad = int(np.flatnonzero(~np.isfinite(V).all(axis=1))[0])
            raise SolverError(f"The reproduction from start {bad} diverged: the field returned NaN/inf "
                              f"at step {i}.", hint="check the model's stability, or lower dt.")
        quiet = quiet + 1 if np.all(np.abs(V) < vel_tol) else 0
        if i >= window and (quiet >= window or i >= max_steps - 1):
            return [out[:i, s].copy() for s in range(m)]
        with np.errstate(over="ignore", invalid="ignore"):
            X = X + dt * V


# ---------------------------------------------------------------- dynamic time warping


def dtw_cumulative(a, b) -> float:
    """Protocol step 3: ``min_P sum_{(i, j) in P} ||a_i - b_j||`` over warping paths P.

    P runs from (0, 0) to (N-1, M-1) with steps (1, 0), (0, 1), (1, 1) and no window; the
    recurrence is ``D[i, j] = ||a_i - b_j|| + min(D[i-1, j-1], D[i-1, j], D[i, j-1])``. The
    cost is symmetric in (a, b), so rows run over the shorter curve (r of them) and each row
    of the longer one (length L) is computed at once: with ``u_j = min(D[i-1, j-1], D[i-1, j])``
    and the row's prefix sums ``S_j = sum_{l <= j} c_l``, ``D[i, j] = S_j + min_{k <= j}
    (u_k - S_{k-1})`` (a cumulative minimum). O(r L) time and memory (the cost matrix);
    about 0.05 s for 3000 x 500 points.
    """
    A, B = _positions(a, "first curve"), _positions(b, "second curve")
    if A.shape[1] != B.shape[1]:
        raise InputError(f"The curves have dimensions {A.shape[1]} and {B.shape[1]}; they must match.")
    short, long_ = (A, B) if len(A) <= len(B) else (B, A)
    check_bytes(8.0 * len(short) * len(long_), f"DTW of {len(A)} x {len(B)} points (the cost matrix)",
                "subsample the curves")
    S = np.cumsum(cdist(short, long_), axis=1)            # S[i, j] = sum_{l <= j} ||short_i - long_l||
    row, u = S[0], np.empty(len(long_))
    for prefix in S[1:]:
        u[0] = row[0]
        np.minimum(row[1:], row[:-1], out=u[1:])
        u[1:] -= prefix[:-1]
        np.minimum.accumulate(u, out=u)
        row = prefix + u
    return float(row[-1])


def nearest_demo_score(train, test) -> float:
    """The "copy" baseline: ``mean_i min_j DTWD(train_j, test_i)`` (whole curves, in L).

    A model that reproduced, for every test demonstration, the training demonstration
    closest to it in DTWD would score this. ``train``, ``test``: demonstrations or arrays (T, n).
    """
    train, test = list(train), list(test)
    if not train or not test:
        raise InputError(f"Need at least one training and one test curve, got {len(train)} and {len(test)}.")
    return float(np.mean([min(dtw_cumulative(tr, te) for tr in train) for te in test]))


# ---------------------------------------------------------------- one shape


def evaluate_shape(fit_fn: Callable, demos) -> dict:
    """The whole protocol on one shape's demonstrations (7, e.g. ``sosdyn.load_lasa(name)``).

    ``fit_fn(train)`` gets the training :class:`Demonstrations` and returns a field
    ``X (m, n) -> Xdot (m, n)`` or a model with ``.predict`` (its goal is its own). Returns
    ``name``; ``dtwd_test`` (3 values) and ``dtwd_test_mean``; ``dtwd_train`` (4) and
    ``dtwd_train_mean`` (reproductions from the training demos' 20th points, as ds-opt also
    reports); ``nearest_demo`` (:func:`nearest_demo_score`); ``n_points_test`` /
    ``n_points_train`` (reproduction lengths; ``MAX_STEPS - 1`` = not converged); ``fit_s``
    and ``reproduce_s`` (wall time, s). A reproduction that diverges (SolverError) scores inf
    and its message is kept in ``failure``.
    """
    train, test = split(demos)
    t0 = time.perf_counter()
    model = fit_fn(train)
    fit_s = time.perf_counter() - t0
    field = getattr(model, "predict", model)
    if not callable(field):
        raise InputError("fit_fn must return a field X -> Xdot or a model with .predict(X).")
    result = {"name": getattr(demos, "name", ""), "fit_s": fit_s, "failure": None}
    t0 = time.perf_counter()
    for part, curves in (("train", train), ("test", test)):
        try:
            reps = euler_reproduce(field, start_points(curves))
        except SolverError as exc:
            result.update({f"dtwd_{part}": [np.inf] * len(curves), f"dtwd_{part}_mean": np.inf,
                           f"n_points_{part}": 0, "failure": str(exc)})
            continue
        scores = [dtw_cumulative(r, d.pos) for r, d in zip(reps, curves)]
        result.update({f"dtwd_{part}": scores, f"dtwd_{part}_mean": float(np.mean(scores)),
                       f"n_points_{part}": len(reps[0])})
    result["reproduce_s"] = time.perf_counter() - t0
    result["nearest_demo"] = nearest_demo_score(train, test)
    return result


# ---------------------------------------------------------------- published numbers


def load_seds_published(path) -> dict[str, dict[str, float]]:
    """Per-shape published SEDS results from a CSV with a ``shape`` column and numeric columns
    (e.g. ``dtwd_test_mean``): ``{shape: {column: value}}``."""
    path = Path(path)
    try:
        with open(path, newline="") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as exc:
        raise InputError(f"Cannot read {path}: {exc}. Try: the path of seds_lasa_published.csv.") from exc
    if not rows or "shape" not in rows[0]:
        raise InputError(f"{path} has no 'shape' column (columns: {list(rows[0]) if rows else []}).")
    out = {}
    for k, row in enumerate(rows, start=2):
        try:
            out[row["shape"]] = {key: float(value) for key, value in row.items() if key != "shape"}
        except (TypeError, ValueError) as exc:
            raise InputError(f"{path} line {k}: a value is not a number ({exc}).") from exc
    return out


__all__ = [
    "SINGLE_PATTERN_SHAPES", "split", "start_points", "euler_reproduce", "dtw_cumulative",
    "nearest_demo_score", "evaluate_shape", "load_seds_published",
]

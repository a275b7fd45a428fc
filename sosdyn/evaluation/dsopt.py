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
3. DTWD = cumulative Euclidean dynamic time warping (:func:`sosdyn.evaluation.metrics.dtwd`)
   between the reproduction and the whole 500-point demonstration (no window; steps (1,0),
   (0,1), (1,1)); mean over the 3 test
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
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.metrics import curve, dtwd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.rollout import euler_until_rest
from sosdyn.lfd.rollout.quality import GOAL_FRACTION, arrival_time, excursion

TRAIN_DEMOS = (0, 1, 2, 3)          # 0-based indices of the training demonstrations (1-4)
TEST_DEMOS = (4, 5, 6)              # and of the test demonstrations (5-7)
#: Named splits, name -> (train, test) 0-based indices: the protocol's, and the one that swaps the
#: roles of the two ends (train on demos 4-7, test on 1-3) to check that a choice holds on other data.
SPLITS = {"standard": (TRAIN_DEMOS, TEST_DEMOS), "swapped": ((3, 4, 5, 6), (0, 1, 2))}
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


# ---------------------------------------------------------------- train / test split


def split(demos, train=TRAIN_DEMOS, test=TEST_DEMOS) -> tuple[Demonstrations, Demonstrations]:
    """Protocol step 1: (train, test) = the demonstrations at the 0-based indices ``train`` and
    ``test`` (default 1-4 and 5-7; :data:`SPLITS` names others), every 2nd sample kept.

    Sample k of a kept demonstration is sample 2k of the original (k = 0, 1, ...; the last
    original sample is dropped when T is even, as MATLAB's ``1:2:end`` drops it), with its
    own time stamp and its recorded velocity: ``vel`` stays the derivative at ``t``, since
    subsampling changes which instants are kept, not what was measured at them.
    """
    items = list(demos)
    train, test = tuple(train), tuple(test)
    if not train or not test or set(train) & set(test) or not all(
            isinstance(i, (int, np.integer)) and i >= 0 for i in train + test):
        raise InputError(f"train {train} and test {test} must be non-empty, disjoint tuples of 0-based "
                         "demonstration indices. Try: one of sosdyn.evaluation.dsopt.SPLITS.")
    needed = max(train + test) + 1
    if len(items) < needed:
        raise InputError(
            f"The split needs {needed} demonstrations (train {[i + 1 for i in train]}, test "
            f"{[i + 1 for i in test]}), got {len(items)}. Try: a LASA shape (sosdyn.load_lasa), which has 7.")
    for i, d in enumerate(items):
        if not isinstance(d, Demonstration):
            raise InputError(f"Item {i} is a {type(d).__name__}, not a Demonstration.")
    name, units = getattr(demos, "name", ""), getattr(demos, "units", "")

    def keep(indices):
        return Demonstrations(
            [Demonstration(d.t[::SAMPLE_STEP], d.pos[::SAMPLE_STEP], d.vel[::SAMPLE_STEP], d.source)
             for d in (items[i] for i in indices)], name, units)

    return keep(train), keep(test)


def start_points(demos) -> np.ndarray:
    """The reproductions' starts: the 20th kept point of each demonstration, (m, n)."""
    curves = [curve(d, f"demonstration {i}") for i, d in enumerate(demos)]
    short = [i for i, c in enumerate(curves) if len(c) <= START_INDEX]
    if short:
        raise InputError(f"Demonstration {short[0]} has {len(curves[short[0]])} samples; the protocol "
                         f"starts at sample {START_INDEX + 1}. Try: longer demonstrations.")
    return np.array([c[START_INDEX] for c in curves])


# ---------------------------------------------------------------- reproduction


def euler_reproduce(field: Callable[[np.ndarray], np.ndarray], starts, dt: float = DT,
                    max_steps: int = MAX_STEPS, vel_tol: float = VEL_TOL,
                    window: int = WINDOW) -> list[np.ndarray]:
    """Protocol step 2: :func:`sosdyn.lfd.rollout.euler_until_rest` with the protocol's constants.

    ``X_{i+1} = X_i + dt field(X_i)`` from all rows of ``starts`` (m, n) at once, stopped at the
    first i >= ``window`` at which every velocity component of every start was below
    ``vel_tol`` at steps i-window+1..i, or at i = ``max_steps`` - 1 (``Simulation.m`` stops at
    ``i > i_max - 2``). Returns m arrays (i, n): x_1..x_i (the last update is dropped as in
    ``Simulation.m``). InputError for another output shape, SolverError when a start diverges.
    """
    return euler_until_rest(field, starts, dt=dt, max_steps=max_steps, vel_tol=vel_tol, window=window)


def nearest_demo_score(train, test) -> float:
    """The "copy" baseline: ``mean_i min_j DTWD(train_j, test_i)`` (whole curves, in L).

    A model that reproduced, for every test demonstration, the training demonstration
    closest to it in DTWD would score this. ``train``, ``test``: demonstrations or arrays (T, n).
    """
    train, test = list(train), list(test)
    if not train or not test:
        raise InputError(f"Need at least one training and one test curve, got {len(train)} and {len(test)}.")
    return float(np.mean([min(dtwd(tr, te).total for tr in train) for te in test]))


# ---------------------------------------------------------------- one shape


def _reproduce(field: Callable, curves) -> tuple[list[np.ndarray] | None, str | None]:
    """Protocol step 2 from the 20th points of ``curves``: (reproductions, None), or (None, the
    message) when a reproduction diverges (SolverError)."""
    try:
        return euler_reproduce(field, start_points(curves)), None
    except SolverError as exc:
        return None, str(exc)


def reproduction_scores(field: Callable, curves) -> tuple[list[float], int, str | None]:
    """Protocol steps 2-3 on ``curves`` (demonstrations): (DTWD of each reproduction from its
    20th point, reproduction length, None); a diverging reproduction (SolverError) scores inf
    for every curve, length 0, and its message."""
    reps, failure = _reproduce(field, curves)
    if reps is None:
        return [np.inf] * len(curves), 0, failure
    return [dtwd(r, d.pos).total for r, d in zip(reps, curves)], len(reps[0]), None


def reproduction_quality(reps, train, curves, goal, dt: float = DT) -> list[dict]:
    """Beyond DTWD, per reproduction ``reps[i]`` (sampled every ``dt``) of ``curves[i]`` from its
    20th point: ``arrival_s`` (first time within 1 % of the training box's diagonal of ``goal``;
    inf = never), ``duration_s`` (the demo's remaining duration from that point),
    ``arrival_ratio``, ``excursion`` (farthest point outside the training box / its diagonal)
    and ``final_error`` (distance from the reproduction's end to the demo's end / diagonal);
    :mod:`sosdyn.lfd.rollout.quality`."""
    pos = np.vstack([d.pos for d in train])
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    rows = []
    for path, d in zip(reps, curves):
        remaining = float(d.t[-1] - d.t[START_INDEX])
        arrival = arrival_time(path, dt, goal, GOAL_FRACTION * diag)
        rows.append({"arrival_s": arrival, "duration_s": remaining, "arrival_ratio": arrival / remaining,
                     "excursion": excursion(path, lo, hi),
                     "final_error": float(np.linalg.norm(path[-1] - d.pos[-1]) / diag)})
    return rows


def select_fit(fit_fns: Mapping[str, Callable], train) -> tuple[str, object, dict[str, float]]:
    """Model selection on the training demonstrations only: fit every candidate
    ``fit_fns[name](train)`` and keep the one whose protocol reproductions from the training
    demonstrations' own 20th points are closest to them (lowest mean DTWD,
    :func:`reproduction_scores`; ties: first name). Nothing but ``train`` is seen, so test
    demonstrations cannot leak into the choice. Returns (name, model, {name: training DTWD})."""
    if not fit_fns:
        raise InputError("select_fit needs at least one candidate. Try: {'ica': fit_a, 'cubic': fit_b}.")
    models, scores = {}, {}
    for name, fit_fn in fit_fns.items():
        models[name] = fit_fn(train)
        scores[name] = float(np.mean(reproduction_scores(getattr(models[name], "predict", models[name]),
                                                         train)[0]))
    best = min(scores, key=scores.get)
    return best, models[best], scores


def evaluate_shape(fit_fn: Callable, demos, train=TRAIN_DEMOS, test=TEST_DEMOS) -> dict:
    """The whole protocol on one shape's demonstrations (7, e.g. ``sosdyn.load_lasa(name)``),
    split by :func:`split` with ``train`` / ``test`` (default demos 1-4 / 5-7).

    ``fit_fn(train)`` gets the training :class:`Demonstrations` and returns a field
    ``X (m, n) -> Xdot (m, n)`` or a model with ``.predict`` (its goal is its own). Returns
    ``name``; ``dtwd_test`` (3 values) and ``dtwd_test_mean``; ``dtwd_train`` (4) and
    ``dtwd_train_mean`` (reproductions from the training demos' 20th points, as ds-opt also
    reports); ``nearest_demo`` (:func:`nearest_demo_score`); ``n_points_test`` /
    ``n_points_train`` (reproduction lengths; ``MAX_STEPS - 1`` = not converged);
    ``arrival_ratio_test``, ``excursion_test``, ``final_error_test`` (the worst test demo's,
    :func:`reproduction_quality`); ``fit_s``
    and ``reproduce_s`` (wall time, s). A reproduction that diverges (SolverError) scores inf
    and its message is kept in ``failure``.
    """
    train, test = split(demos, train, test)
    t0 = time.perf_counter()
    model = fit_fn(train)
    fit_s = time.perf_counter() - t0
    field = getattr(model, "predict", model)
    if not callable(field):
        raise InputError("fit_fn must return a field X -> Xdot or a model with .predict(X).")
    result = {"name": getattr(demos, "name", ""), "fit_s": fit_s, "failure": None}
    t0 = time.perf_counter()
    goal = np.asarray(getattr(model, "goal_", train.goal), dtype=float)
    for part, curves in (("train", train), ("test", test)):
        reps, failure = _reproduce(field, curves)
        scores = [np.inf] * len(curves) if reps is None else [dtwd(r, d.pos).total for r, d in zip(reps, curves)]
        result.update({f"dtwd_{part}": scores, f"dtwd_{part}_mean": float(np.mean(scores)),
                       f"n_points_{part}": 0 if reps is None else len(reps[0])})
        result["failure"] = failure or result["failure"]
    rows = reproduction_quality(reps, train, test, goal) if reps is not None else []
    for key in ("arrival_ratio", "excursion", "final_error"):     # the worst test demo
        result[f"{key}_test"] = max((r[key] for r in rows), default=np.inf)
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
    "SINGLE_PATTERN_SHAPES",
    "SPLITS",
    "euler_reproduce",
    "evaluate_shape",
    "load_seds_published",
    "nearest_demo_score",
    "reproduction_quality",
    "reproduction_scores",
    "select_fit",
    "split",
    "start_points",
]

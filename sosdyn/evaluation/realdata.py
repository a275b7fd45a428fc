"""A held-out accuracy protocol on real demonstrations (``make real-data``), after ds-opt's.

Per set of N demonstrations (in the set's order):

1. Split: the first ceil(4N/7) train, the rest test (LASA's 4 of 7).
2. Training data: :func:`sosdyn.lfd.data.preprocess.preprocess` with its defaults, chosen from
   the training demonstrations only, then every 2nd sample (as ds-opt). Test data: the
   resting samples trimmed with the training noise level (no smoothing, no alignment: scored
   against what was recorded), every 2nd sample.
3. Reproduction: ds-opt's explicit Euler (:func:`sosdyn.evaluation.dsopt.euler_reproduce`,
   dt = 0.01 s) from each test demo's 20th kept sample, with the stop rule scaled to the
   data: rest when every velocity component stays below ``VEL_TOL_FRACTION * diag / T_med``
   (diag: the training box's diagonal, T_med: the median training duration; on LASA this is
   ds-opt's 0.1 mm/s), at most ``max(30 s, HORIZON x the longest test duration)``.
4. Scores per test demo: DTWD to the whole kept demo (:func:`~sosdyn.evaluation.metrics.dtwd`);
   copy = min over training demos of their DTWD to it (:func:`~sosdyn.evaluation.dsopt.nearest_demo_score`);
   arrival = the first time within 1 % of diag of the model's goal, over the demo's remaining
   duration from the start sample (inf: never); excursion = farthest point outside the training
   box / diag (:func:`sosdyn.lfd.rollout.quality.excursion`); start excursion = the start's own;
   certified excursion bound = the largest excursion of the box that the certificate keeps the
   trajectory in (:func:`sosdyn.lfd.model.reach.reach_box`, docs/theory.md; None without a
   certified constant metric); final error = distance from the reproduction's end to the demo's
   end / diag.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation import dsopt
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.preprocess import REST_NOISE, preprocess, rest_bounds
from sosdyn.lfd.model.reach import reach_box
from sosdyn.lfd.rollout.quality import box_excursion, excursion

TRAIN_FRACTION = 4 / 7
VEL_TOL_FRACTION = 0.006      # ds-opt's 0.1 mm/s over a LASA shape's diag / duration (~65 mm / 4 s)
HORIZON = 2.5                 # reproductions may run this many test durations (at least 30 s)
PATH_POINTS = 300             # reproduction points kept for figures


def split_first(demos) -> tuple[Demonstrations, Demonstrations]:
    """(train, test): the first ceil(4N/7) demonstrations and the rest; InputError for N < 2."""
    items = list(demos)
    if len(items) < 2:
        raise InputError(f"a held-out split needs at least 2 demonstrations, got {len(items)}. "
                         "Try: a set with several demonstrations of one motion.")
    k = math.ceil(TRAIN_FRACTION * len(items))
    name, units = getattr(demos, "name", ""), getattr(demos, "units", "")
    return Demonstrations(items[:k], name, units), Demonstrations(items[k:], name, units)


def _every_second(demos) -> Demonstrations:
    return Demonstrations([Demonstration(d.t[::dsopt.SAMPLE_STEP], d.pos[::dsopt.SAMPLE_STEP],
                                         d.vel[::dsopt.SAMPLE_STEP], d.source) for d in demos],
                          demos.name, demos.units)


def prepare(demos):
    """Protocol steps 1-2: (train for fitting, train as recorded, test, preprocessing report)."""
    train, test = split_first(demos)
    fitted, report = preprocess(train)
    tol = REST_NOISE * report.noise

    def trim(d):
        a, b = rest_bounds(d.pos, tol)
        return Demonstration(d.t[a:b + 1], d.pos[a:b + 1], d.vel[a:b + 1], d.source)

    return (_every_second(fitted), _every_second(Demonstrations([trim(d) for d in train], demos.name, demos.units)),
            _every_second(Demonstrations([trim(d) for d in test], demos.name, demos.units)), report)


def box(demos) -> tuple[np.ndarray, np.ndarray, float]:
    """(lo, hi, diagonal) of the bounding box of all positions."""
    pos = np.vstack([d.pos for d in demos])
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    return lo, hi, float(np.linalg.norm(hi - lo))


def stop_rule(train, test) -> tuple[float, int]:
    """Protocol step 3's (vel_tol, max_steps): ``VEL_TOL_FRACTION * diag / T_med`` and
    ``max(30 s, HORIZON x the longest test duration) / dt``."""
    _, _, diag = box(train)
    vel_tol = VEL_TOL_FRACTION * diag / float(np.median([d.duration for d in train]))
    horizon = max(dsopt.MAX_STEPS * dsopt.DT, HORIZON * max(d.duration for d in test))
    return vel_tol, int(math.ceil(horizon / dsopt.DT))


def reproduce(field: Callable, train, test) -> list[np.ndarray]:
    """Protocol step 3 from the test demos' 20th kept samples."""
    vel_tol, max_steps = stop_rule(train, test)
    return dsopt.euler_reproduce(field, dsopt.start_points(test), vel_tol=vel_tol, max_steps=max_steps)


def excursion_bounds(model, train, test) -> list:
    """Per test start (the 20th kept sample): the certified excursion bound, the largest
    excursion outside ``train``'s box of any state in ``model``'s reach box from it
    (:func:`~sosdyn.lfd.model.reach.reach_box`); None for each when the model is not certified or
    its metric is not constant."""
    reach = reach_box(model, dsopt.start_points(test)) if getattr(model, "certified_", None) else None
    if reach is None:
        return [None] * len(test)
    lo, hi, _ = box(train)
    return [float(b) for b in box_excursion(*reach, lo, hi)]


def test_scores(paths, train, test, goal, bounds=None) -> list[dict]:
    """Protocol step 4: one row per test demo, DTWD, copy, the start's own excursion and the
    certified bound (``bounds``, :func:`excursion_bounds`; None) added to
    :func:`sosdyn.evaluation.dsopt.reproduction_quality`'s arrival, excursion and final error."""
    rows = dsopt.reproduction_quality(paths, train, test, goal)
    lo, hi, _ = box(train)
    bounds = [None] * len(test) if bounds is None else bounds
    return [dict(r, dtwd=dtwd(path, d.pos).total, copy=min(dtwd(tr.pos, d.pos).total for tr in train),
                 start_excursion=excursion(x0[None], lo, hi), excursion_bound=b, n_points=len(path))
            for r, path, d, x0, b in zip(rows, paths, test, dsopt.start_points(test), bounds)]


def thin(path: np.ndarray, n: int = PATH_POINTS) -> np.ndarray:
    """At most ``n`` rows of ``path``, evenly spaced, first and last kept."""
    return path[np.unique(np.linspace(0, len(path) - 1, min(n, len(path))).astype(int))]


def evaluate_set(fit_fn: Callable, demos) -> dict:
    """The whole protocol on one set: ``fit_fn(train)`` returns a model with ``predict`` (and
    ``goal_``; else the training goal is used). Returns the per-test rows (``tests``), their
    means (``dtwd_mean``, ``copy_mean``, ``ratio`` = dtwd_mean / copy_mean), the worst
    ``excursion``, ``start_excursion``, ``excursion_bound`` (None without one), ``arrival_ratio``
    and ``final_error``, ``fit_s``, ``certified`` (None for a
    model without a certificate), the preprocessing summary, the reproductions (thinned) and,
    for a diverging reproduction, ``failure`` (then no scores)."""
    train, recorded, test, report = prepare(demos)
    t0 = time.perf_counter()
    model = fit_fn(train)
    fit_s = time.perf_counter() - t0
    goal = np.asarray(getattr(model, "goal_", train.goal), dtype=float)
    out = {"name": getattr(demos, "name", ""), "n_train": len(train), "n_test": len(test), "fit_s": fit_s,
           "certified": getattr(model, "certified_", None), "preprocess": report.lines(demos.units),
           "smoothing_window": report.window, "failure": None}
    try:
        paths = reproduce(model.predict, recorded, test)
    except SolverError as exc:
        return dict(out, failure=str(exc))
    rows = test_scores(paths, recorded, test, goal, excursion_bounds(model, recorded, test))
    bounds = [r["excursion_bound"] for r in rows]
    dtwd_mean, copy_mean = float(np.mean([r["dtwd"] for r in rows])), float(np.mean([r["copy"] for r in rows]))
    return dict(out, tests=rows, dtwd_mean=dtwd_mean, copy_mean=copy_mean, ratio=dtwd_mean / copy_mean,
                excursion=max(r["excursion"] for r in rows), start_excursion=max(r["start_excursion"] for r in rows),
                excursion_bound=None if None in bounds else max(bounds), arrival_ratio=max(r["arrival_ratio"] for r in rows),
                final_error=max(r["final_error"] for r in rows), paths=[thin(p) for p in paths])

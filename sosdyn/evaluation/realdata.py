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
   ds-opt's 0.1 mm/s), at most ``max(30 s, HORIZON x the longest test duration)``. A
   time-indexed model (``time_indexed`` True: a DMP, no field) runs its own rollout from the start
   for that horizon at dt, cut by the same rest rule (:func:`rest_cut`).
4. Scores per test demo: DTWD to the whole kept demo (:func:`~sosdyn.evaluation.metrics.dtwd`) of
   the reproduction **read at the demo's period** (:func:`at_period`: linear interpolation in time
   at the kept demo's mean sample step), so the two curves are sampled alike: the cumulative DTW
   adds one term per point, and a rollout at 0.01 s against demos kept at 2/60 s (robottasks) or
   0.02 s would count 3.3x or 2x the points of the demo it is compared with (ds-opt's LASA
   protocol needs no reading: its rollout step, 0.01 s, is LASA's kept period, 0.009 s);
   copy = min over training demos of their DTWD to it (:func:`~sosdyn.evaluation.dsopt.nearest_demo_score`;
   demos of one recording share the period);
   arrival = the first time within 1 % of diag of the model's goal, over the demo's remaining
   duration from the start sample (inf: never); excursion = farthest point outside the training
   box / diag (:func:`sosdyn.lfd.rollout.quality.excursion`); start excursion = the start's own;
   excursion beyond the start = farthest point outside the training box widened to hold the
   start, / diag (what a rollout adds to where it starts); certified excursion bound = the largest
   excursion of the box that the certificate keeps the trajectory in
   (:func:`sosdyn.lfd.model.reach.reach_box`, docs/theory.md; None without a certified constant
   metric); final error = distance from the reproduction's end to the demo's end / diag.
   Arrival, excursions and final error read the whole rollout (every dt).
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


def rest_cut(path: np.ndarray, vel_tol: float, dt: float = dsopt.DT, window: int = dsopt.WINDOW) -> np.ndarray:
    """``path`` (rows every ``dt``) up to the first row i >= ``window`` at which every component of
    the finite-difference velocity (x_{j+1} - x_j) / dt stayed below ``vel_tol`` for j = i-window+1..i
    (the Euler stop rule of :func:`~sosdyn.lfd.rollout.euler_until_rest` read off the positions);
    the whole path if it never rests."""
    calm = (np.abs(np.diff(path, axis=0)) / dt < vel_tol).all(axis=1).astype(int)
    if len(calm) < window:
        return path
    run = np.convolve(calm, np.ones(window, dtype=int), mode="valid")        # calm steps in each window
    at = np.flatnonzero(run == window)
    return path if not at.size else path[:at[0] + window]


def reproduce_model(model, train, test) -> list[np.ndarray]:
    """Protocol step 3 for a fitted model: :func:`reproduce` of its field ``predict``, or for a
    time-indexed model (``time_indexed``: a DMP) its ``rollout`` from each start at dt for the
    horizon, cut at rest (:func:`rest_cut`)."""
    if not getattr(model, "time_indexed", False):
        return reproduce(model.predict, train, test)
    vel_tol, max_steps = stop_rule(train, test)
    return [rest_cut(model.rollout(x0, (max_steps - 1) * dsopt.DT, dt=dsopt.DT).pos, vel_tol)
            for x0 in dsopt.start_points(test)]


def at_period(path: np.ndarray, demo, dt: float = dsopt.DT) -> np.ndarray:
    """The reproduction ``path`` (row k at time k ``dt``) read every mean sample step of ``demo``
    (its kept samples' (t_last - t_first) / (T - 1)), from 0 to the path's end, by linear
    interpolation in time: the curve at the demo's period, for the cumulative DTW (module docstring)."""
    period = float(demo.t[-1] - demo.t[0]) / (len(demo.t) - 1)
    t = np.arange(len(path)) * dt
    tq = np.arange(0.0, t[-1] + 1e-9 * period, period)
    return np.column_stack([np.interp(tq, t, path[:, k]) for k in range(path.shape[1])])


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


def test_scores(paths, train, test, goal, bounds=None, alike: bool = True) -> list[dict]:
    """Protocol step 4: one row per test demo, DTWD (of the path read at the demo's period,
    :func:`at_period`; as integrated for ``alike`` False, ds-opt's LASA protocol), copy, the
    start's own excursion, the excursion beyond the start and the certified bound (``bounds``,
    :func:`excursion_bounds`; None) added to :func:`sosdyn.evaluation.dsopt.reproduction_quality`'s
    arrival, excursion and final error."""
    rows = dsopt.reproduction_quality(paths, train, test, goal)
    lo, hi, diag = box(train)
    bounds = [None] * len(test) if bounds is None else bounds
    out = []
    for r, path, d, x0, b in zip(rows, paths, test, dsopt.start_points(test), bounds):
        wide_lo, wide_hi = np.minimum(lo, x0), np.maximum(hi, x0)
        beyond = excursion(path, wide_lo, wide_hi) * float(np.linalg.norm(wide_hi - wide_lo)) / diag
        out.append(dict(r, dtwd=dtwd(at_period(path, d) if alike else path, d.pos).total,
                        copy=min(dtwd(tr.pos, d.pos).total for tr in train), start_excursion=excursion(x0[None], lo, hi),
                        excursion_beyond_start=beyond, excursion_bound=b, n_points=len(path)))
    return out


def thin(path: np.ndarray, n: int = PATH_POINTS) -> np.ndarray:
    """At most ``n`` rows of ``path``, evenly spaced, first and last kept."""
    return path[np.unique(np.linspace(0, len(path) - 1, min(n, len(path))).astype(int))]


def evaluate_set(fit_fn: Callable, demos) -> dict:
    """The whole protocol on one set: ``fit_fn(train)`` returns a model with ``predict`` (and
    ``goal_``; else the training goal is used), or a time-indexed one with ``rollout``
    (:func:`reproduce_model`). Returns the per-test rows (``tests``), their
    means (``dtwd_mean``, ``copy_mean``, ``ratio`` = dtwd_mean / copy_mean), the worst
    ``excursion``, ``start_excursion``, ``excursion_beyond_start``, ``excursion_bound`` (None without one), ``arrival_ratio``
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
        paths = reproduce_model(model, recorded, test)
    except SolverError as exc:
        return dict(out, failure=str(exc))
    rows = test_scores(paths, recorded, test, goal, excursion_bounds(model, recorded, test))
    bounds = [r["excursion_bound"] for r in rows]
    dtwd_mean, copy_mean = float(np.mean([r["dtwd"] for r in rows])), float(np.mean([r["copy"] for r in rows]))
    return dict(out, tests=rows, dtwd_mean=dtwd_mean, copy_mean=copy_mean, ratio=dtwd_mean / copy_mean,
                excursion=max(r["excursion"] for r in rows), start_excursion=max(r["start_excursion"] for r in rows),
                excursion_beyond_start=max(r["excursion_beyond_start"] for r in rows),
                excursion_bound=None if None in bounds else max(bounds), arrival_ratio=max(r["arrival_ratio"] for r in rows),
                final_error=max(r["final_error"] for r in rows), paths=[thin(p) for p in paths])

"""Fit one method on one shape and score it: the entry every experiment reports from.

:func:`fit_and_evaluate` fits the method, scores the reproductions of the demonstrations
(SEA, DTWD, goal error, velocity RMSE), the robustness protocol (the same seeded pushes and
goal changes for every method, :mod:`sosdyn.evaluation.perturbations`), convergence from a
grid of starts, the certificate, the timings, and keeps the data the figures need
(reproductions, one pushed and one goal-changed run, the field on the plot lattice). The
entry is JSON-able and cached (:mod:`problems.cache`), so figures and the report are
rebuilt without refitting.
"""
from __future__ import annotations

import time
import traceback
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from sosdyn.evaluation.convergence import grid_convergence, grid_convergence_budget
from sosdyn.evaluation.metrics import goal_error, velocity_rmse
from sosdyn.evaluation.perturbations import make_events, robustness
from sosdyn.evaluation.reproduction import (describe, evaluate_reproductions, rollout_function,
                                            rollout_to_goal)
from sosdyn.lfd.rollout import BudgetRollout

from .cache import cache_key, key_hash, read_cache, write_cache
from .jsonio import jsonable, rounded
from .lattice import field_on_lattice, plot_bounds
from .settings import METHODS, EvalConfig, Method, Shape, load_shape, shape


def trajectory_json(traj, every=1) -> dict | None:
    """A rollout (positions, goal history, events) as rounded JSON, every ``every``-th sample."""
    if traj is None:
        return None
    return {"pos": rounded(traj.pos[::every]), "goal_history": rounded(traj.goal_history[::every]),
            "events": [{"kind": e["kind"], "time": float(e["time"]), "before": rounded(e["before"]),
                        "after": rounded(e["after"])} for e in traj.events]}


def fit_and_evaluate(shp: Shape | str, method: str, quick: bool = False, *,
                     config: EvalConfig | None = None, cache_dir: Path | None = None,
                     force: bool = False) -> dict:
    """Fit ``method`` on ``shp`` and score it; the entry is cached (module docstring).

    Returns ``{"shape", "method", "status" ("ok"/"failed"), "error", "accuracy",
    "robustness", "certificate", "timings", "diagnostics", "plot", "eval_s"}`` where
    ``accuracy``/``robustness``/``certificate``/``timings`` are this pair's entries of the
    results schema (:mod:`sosdyn.report.html`). A failing fit is recorded, not raised.
    """
    shp = shape(shp) if isinstance(shp, str) else shp
    config = config or EvalConfig(quick=quick)
    if not force:
        cached = read_cache(shp, method, config, cache_dir)
        if cached is not None:
            cached["from_cache"] = True
            return cached
    with threadpool_limits(1), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        try:
            entry = evaluate(shp, METHODS[method], config)
        except Exception as exc:            # a failed fit is a result, reported as such
            entry = {"status": "failed", "error": f"{type(exc).__name__}: {exc}",
                     "traceback": traceback.format_exc(limit=6)}
        entry["eval_s"] = time.perf_counter() - t0
    messages = sorted({f"{w.category.__name__}: {str(w.message).splitlines()[0][:200]}" for w in caught})
    key = cache_key(shp, method, config)
    entry.update(shape=shp.name, K=shp.K, method=method, warnings=messages[:10],
                 key=key, key_hash=key_hash(key), from_cache=False)
    entry = jsonable(entry)
    write_cache(entry, shp, method, config, cache_dir)
    return entry


def evaluate(shp: Shape, method: Method, config: EvalConfig) -> dict:
    """Fit and score (no cache, errors raised): the entry without its identification."""
    demos = load_shape(shp, config)
    model = method.factory(shp, config.quick)
    t0 = time.perf_counter()
    model.fit(demos)
    fit_s = time.perf_counter() - t0
    autonomous = method.kind != "dmp"
    roll = BudgetRollout(model) if autonomous else model
    accuracy, rep, acc_s = _accuracy(model, roll, demos, method, fit_s)
    rob, exemplars, rob_s = _robustness(roll, demos, config)
    grid, integrator, grid_s = _grid(model, demos, config, autonomous)
    accuracy["grid_convergence"] = None if grid is None else float(grid.fraction)
    entry = {"status": "ok", "error": None, "accuracy": accuracy, "robustness": rob,
             "certificate": None, "timings": {"em_s": None, "build_s": None, "solve_s": None,
                                              "verify_s": None, "total_s": fit_s},
             "diagnostics": {"eval_times_s": {"accuracy": acc_s, "robustness": rob_s, "grid": grid_s},
                             "grid": {"n_starts": None if grid is None else grid.n_starts,
                                      "integrator": integrator,
                                      "n_failures": None if grid is None else len(grid.failures)},
                             "rollout_bdf_fallbacks": getattr(roll, "fallbacks", 0),
                             "rollout_budget_failures": getattr(roll, "failures", 0)}}
    if method.kind == "cdsp":
        _add_certificate(entry, model, fit_s)
    plot = {"reproductions": _drawn_reproductions(roll, demos, rep["trajectories"], config),
            "exemplars": exemplars}
    if method.plot_field and autonomous:
        bounds = plot_bounds(demos, [t.pos for t in rep["trajectories"]])
        plot["field"] = field_on_lattice(model, bounds, config.field_grid)
    entry["plot"] = plot
    return entry


def _accuracy(model, roll, demos, method: Method, fit_s: float):
    """Reproductions of every demonstration from its first point: (accuracy, raw, seconds)."""
    t0 = time.perf_counter()
    rep = evaluate_reproductions(roll, demos)
    seconds = time.perf_counter() - t0
    X, _ = demos.stacked()
    accuracy = {
        "sea": describe(rep["sea"]), "dtwd_total": describe(rep["dtwd"]),
        "dtwd_per_point": describe(rep["dtwd_per_point"]),
        "vel_rmse": float(velocity_rmse(model, demos)) if method.kind != "dmp" else None,
        "goal_error": describe(rep["goal_error"]),
        "grid_convergence": None, "n_points": int(X.shape[0]), "fit_time_s": fit_s,
        "certified": bool(model.certified_) if method.kind == "cdsp" else None,
    }
    return accuracy, rep, seconds


def _drawn_reproductions(roll, demos, trajectories, config: EvalConfig) -> list:
    """The reproductions the figures draw: each run continued until it ends within
    ``config.goal_tol`` of the goal (at most ``max_duration_factor`` x its demonstration; the
    scored runs last the demonstration's duration), cut where it first gets there, every
    4th sample."""
    out = []
    for demo, traj in zip(demos, trajectories):
        if goal_error(traj, traj.goal_history[-1]) > config.goal_tol:
            cap = config.max_duration_factor * demo.duration
            traj = rollout_to_goal(rollout_function(roll), demo.pos[0],
                                   min(2.0 * demo.duration, cap), dt=demo.duration / (len(demo.t) - 1),
                                   tol=config.goal_tol, max_duration=cap)
        near = np.linalg.norm(traj.pos - traj.goal_history[-1], axis=1) <= config.goal_tol
        end = int(np.argmax(near)) + 1 if near.any() else len(traj.pos)
        out.append(rounded(traj.pos[:end:4]))
    return out


def _robustness(roll, demos, config: EvalConfig):
    """The same seeded push and goal change for every method: (scores, exemplar runs, seconds)."""
    t0 = time.perf_counter()
    rob, exemplars = {}, {}
    for kind, amp in (("push", config.push_amp), ("goal_change", config.goal_amp)):
        events = make_events(demos, kind, n=1, seed=config.seed, amplitude_frac=amp,
                             at_frac=config.at_frac)
        res = robustness(roll, demos, events, duration_factor=config.duration_factor,
                         tol_mm=config.goal_tol, max_duration_factor=config.max_duration_factor)
        rob[kind] = {"dtwd_total": describe(res["dtwd"]), "goal_error": describe(res["goal_error"]),
                     "converged": float(res["fraction_converged"]),
                     "failures": [f["reason"][:300] for f in res["failures"]]}
        exemplars[kind] = trajectory_json(res["trajectories"][0], every=2)
    return rob, exemplars, time.perf_counter() - t0


def _grid(model, demos, config: EvalConfig, autonomous: bool):
    """Convergence from a grid of starts: (result or None, integrator, seconds)."""
    t0 = time.perf_counter()
    if autonomous:
        grid, integrator = grid_convergence_budget(model, demos, config.n_grid)
    else:
        grid, integrator = grid_convergence(model, demos, n_grid=config.n_grid), "DMP steps"
    return grid, integrator, time.perf_counter() - t0


def _add_certificate(entry: dict, model, fit_s: float) -> None:
    """A CDSP model's certificate, SOS timings and learner diagnostics into ``entry``."""
    ver = model.verification_.as_dict()
    ver.pop("checks", None)
    collapse = model.metric_collapse_
    entry["certificate"] = {
        "min_gram_eig": ver["min_gram_eig"], "max_coeff_residual": ver["max_coeff_residual"],
        "max_sampled_eig": ver["max_sampled_eig"], "n_samples": ver["n_samples"],
        "passed": bool(ver["passed"]),
        "metric_collapse": None if collapse is None else {
            "M(0) certifies": bool(collapse["constant_metric_certifies"]),
            "max eig. with M(0)": float(collapse["max_eig_with_constant_metric"])}}
    hist = model.history_
    tm = model.timings_
    entry["timings"] = {"em_s": tm.get("em_s"),
                        "build_s": float(sum(r.get("build_s", 0.0) for r in hist)),
                        "solve_s": float(sum(r.get("solve_s", 0.0) for r in hist)),
                        "verify_s": tm.get("certify_s", 0.0) + tm.get("verify_s", 0.0),
                        "total_s": tm.get("total_s", fit_s)}
    entry["diagnostics"].update(history=hist, metric_collapse=collapse, gmr_cost=model.gmr_cost_,
                                final_cost=hist[-1]["cost"] if hist else None, verification=ver)

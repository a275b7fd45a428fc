"""Reproductions of demonstrations by a model, and the mean/std summaries every report uses."""

from __future__ import annotations

import numpy as np

from sosdyn.errors import InputError
from sosdyn.evaluation.metrics import as_demonstrations, dtwd, goal_error, sea


def mean_std(values) -> tuple[float, float]:
    """Mean and population (ddof = 0) standard deviation of ``values``; both inf when a value is
    not finite (a failed rollout) or there are none."""
    arr = np.asarray(values, dtype=float)
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        return np.inf, np.inf
    return float(arr.mean()), float(arr.std())


def describe(values) -> dict:
    """``{"mean", "std", "per_demo"}``: :func:`mean_std` and the values as floats (for JSON)."""
    mean, std = mean_std(values)
    return {"mean": mean, "std": std, "per_demo": [float(v) for v in np.asarray(values, dtype=float)]}


def summarize(values: dict[str, list]) -> tuple[dict[str, float], dict[str, float]]:
    """:func:`mean_std` of each list: ``({key: mean}, {key: std})``."""
    stats = {k: mean_std(v) for k, v in values.items()}
    return {k: s[0] for k, s in stats.items()}, {k: s[1] for k, s in stats.items()}


def rollout_function(model):
    """``model.rollout`` if present, else ``model`` itself: called as ``f(x0, duration, dt=...)``."""
    fn = getattr(model, "rollout", model)
    if not callable(fn):
        raise InputError("Pass a model with .rollout(x0, duration, dt=...) or such a function.")
    return fn


def rollout_to_goal(fn, x0, duration: float, *, dt: float, tol: float, max_duration: float, **events):
    """``fn(x0, duration, dt=dt, **events)``, the duration doubled until the run ends within
    ``tol`` of the goal in effect at its end, at most ``max_duration``.

    A run long enough to reach the goal: a slow but convergent model is not scored as stuck
    because its rollout was cut early. Same start, step and events each time, so a longer run
    repeats the shorter one and continues it; the returned run is the first one that ends
    within ``tol``, or the ``max_duration`` one.
    """
    if not 0 < duration <= max_duration or not tol > 0:
        raise InputError(f"Need 0 < duration <= max_duration and tol > 0, got duration={duration!r}, "
                         f"max_duration={max_duration!r}, tol={tol!r}.")
    while True:
        traj = fn(x0, duration, dt=dt, **events)
        if duration >= max_duration or goal_error(traj, traj.goal_history[-1]) <= tol:
            return traj
        duration = min(2.0 * duration, max_duration)


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

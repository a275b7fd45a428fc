"""Robustness protocol: reproductions under sudden pushes and goal changes (CDSP section 3).

Following the guidelines of Lemme et al. (2015), every algorithm sees the same seeded events:
a push (state jump) or a goal change at a fixed fraction of each demo's motion, with a fixed
amplitude relative to the data scale (the diagonal of the bounding box of all positions) and
a random direction drawn from the seed. Event times are in rollout time (0 = start).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.metrics import as_demonstrations, dtwd, goal_error
from sosdyn.evaluation.reproduction import rollout_function, rollout_to_goal, summarize

KINDS = ("push", "goal_change")


class Push(NamedTuple):
    """At ``time`` (s) the state jumps by ``dx`` (L); unpacks as the pair rollout expects."""

    time: float
    dx: np.ndarray


class GoalChange(NamedTuple):
    """From ``time`` (s) on the goal is ``new_goal`` (L)."""

    time: float
    new_goal: np.ndarray


@dataclass(frozen=True)
class Scenario:
    """The events of one perturbed reproduction of demo ``demo_index``."""

    demo_index: int
    pushes: tuple[Push, ...] = ()
    goal_changes: tuple[GoalChange, ...] = ()


def make_events(demos, kind: str, n: int = 1, seed: int = 0, *, amplitude_frac: float = 0.1,
                at_frac: float = 0.3) -> list[Scenario]:
    """``n`` scenarios per demo with one event each, reproducible from ``seed``.

    The event happens at ``at_frac * duration`` of the demo. ``kind="push"``: ``dx = a u``;
    ``kind="goal_change"``: ``new_goal = demos.goal + a u``; with ``a = amplitude_frac *``
    (bounding-box diagonal of all positions) and ``u`` a unit vector drawn uniformly on the
    sphere from ``seed`` (scenario by scenario, demo-major order).
    """
    demos = as_demonstrations(demos)
    if kind not in KINDS:
        raise InputError(f"kind must be one of {KINDS}, got {kind!r}.")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n must be a positive integer, got {n!r}.")
    if not 0 <= at_frac <= 1 or not amplitude_frac >= 0:
        raise InputError(f"Need 0 <= at_frac <= 1 and amplitude_frac >= 0, got at_frac = {at_frac!r}, "
                         f"amplitude_frac = {amplitude_frac!r}.")
    X, _ = demos.stacked()
    amplitude = amplitude_frac * float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    rng = np.random.default_rng(seed)
    scenarios = []
    for i, demo in enumerate(demos):
        for _ in range(n):
            direction = rng.standard_normal(demos.dim)
            offset = amplitude * direction / np.linalg.norm(direction)
            time = at_frac * demo.duration
            if kind == "push":
                scenarios.append(Scenario(i, pushes=(Push(time, offset),)))
            else:
                scenarios.append(Scenario(i, goal_changes=(GoalChange(time, demos.goal + offset),)))
    return scenarios


def shifted_reference(demo, goal_changes, initial_goal) -> np.ndarray:
    """The demo as the perturbed reproduction should look: positions (T, n).

    Each sample at rollout time ``tau = t - t[0]`` is translated by ``g(tau) - initial_goal``,
    where ``g(tau)`` is the goal in effect at ``tau`` (the last change with time <= tau), so
    the part after a goal change is the demo shifted by the goal offset. Pushes leave the
    reference unchanged.
    """
    tau = demo.t - demo.t[0]
    ref = np.array(demo.pos, dtype=float)
    for change in sorted(goal_changes, key=lambda c: c[0]):  # later changes overwrite earlier ones
        ref[tau >= change[0]] = demo.pos[tau >= change[0]] + (np.asarray(change[1]) - initial_goal)
    return ref


def robustness(model, demos, events, *, duration_factor: float = 1.5, tol_mm: float = 1.0,
               max_duration_factor: float | None = None) -> dict:
    """Score perturbed reproductions (scenarios from :func:`make_events`).

    Each scenario rolls out the model from its demo's first point for ``duration_factor x``
    the demo's duration (time to recover), dt = the demo's mean step, at the training goal,
    with the scenario's events; with ``max_duration_factor`` the duration is doubled until
    the run ends within ``tol_mm`` of its goal, at most ``max_duration_factor x`` the demo's
    duration (:func:`~sosdyn.evaluation.reproduction.rollout_to_goal`). Scores: ``dtwd`` / ``dtwd_per_point`` (L) between the
    reproduction and :func:`shifted_reference` (initial goal ``demos.goal``, the training
    goal); ``goal_error`` (L) to the goal in effect at the end; ``converged`` = goal_error
    <= tol_mm. A rollout raising SolverError scores inf / not converged and is listed in
    ``failures``. Returns per-scenario lists, ``trajectories``, ``mean`` / ``std`` (ddof = 0)
    and ``fraction_converged``.
    """
    demos = as_demonstrations(demos)
    fn = rollout_function(model)
    if not duration_factor > 0:
        raise InputError(f"duration_factor must be > 0, got {duration_factor!r}.")
    cap = duration_factor if max_duration_factor is None else max_duration_factor
    if not cap >= duration_factor:
        raise InputError(f"max_duration_factor must be >= duration_factor ({duration_factor!r}), "
                         f"got {max_duration_factor!r}.")
    scores = {"dtwd": [], "dtwd_per_point": [], "goal_error": []}
    converged, trajectories, failures = [], [], []
    for k, scenario in enumerate(events):
        if not isinstance(scenario, Scenario) or not 0 <= scenario.demo_index < len(demos):
            raise InputError(f"events[{k}] must be a Scenario for one of the {len(demos)} demos "
                             f"(see make_events), got {scenario!r}.")
        demo = demos[scenario.demo_index]
        try:
            traj = rollout_to_goal(fn, demo.pos[0], duration_factor * demo.duration,
                                   dt=demo.duration / (len(demo.t) - 1), tol=tol_mm,
                                   max_duration=cap * demo.duration, perturbations=scenario.pushes,
                                   goal_changes=scenario.goal_changes)
        except SolverError as exc:
            failures.append({"scenario": k, "reason": str(exc)})
            for values in scores.values():
                values.append(np.inf)
            converged.append(False)
            trajectories.append(None)
            continue
        distance = dtwd(traj, shifted_reference(demo, scenario.goal_changes, demos.goal))
        error = goal_error(traj, traj.goal_history[-1])
        scores["dtwd"].append(distance.total)
        scores["dtwd_per_point"].append(distance.per_point)
        scores["goal_error"].append(error)
        converged.append(error <= tol_mm)
        trajectories.append(traj)
    if not converged:
        raise InputError("events is empty; build scenarios with make_events.")
    mean, std = summarize(scores)
    return {**scores, "converged": converged, "fraction_converged": float(np.mean(converged)),
            "failures": failures, "trajectories": trajectories, "mean": mean, "std": std}

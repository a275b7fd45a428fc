"""Convergence from a grid of starts: per-start rollouts, or all starts as one batched ODE.

Starts cover the data's bounding box scaled by 2 about its centre (:func:`grid_starts`); a
start converges when its rollout ends within ``tol_mm`` (L) of the goal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.metrics import as_demonstrations, goal_error
from sosdyn.evaluation.reproduction import rollout_function
from sosdyn.lfd.rollout import GRID_BUDGETS, BudgetExceeded, final_states, run_with_budget


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


def grid_convergence_batched(model, demos, n_grid: int = 10, horizon: float | None = None,
                             tol_mm: float = 1.0, *, goal=None, seed: int = 0, integrator: str = "LSODA",
                             rtol: float = 1e-6, atol: float = 1e-8,
                             escape_factor: float = 100.0) -> GridConvergence:
    """:func:`grid_convergence` for an autonomous model, all starts integrated at once.

    ``model`` has ``field(X (m, n), goal) -> Xdot (m, n)`` (the field functions of CDSP, GMR
    and CLF-DM accept many rows) and ``goal_``; or pass the field callable itself and ``goal``
    (default: the demos' goal). Same starts, horizon (default 5 x the longest demo), goal and
    criterion ``||x(horizon) - goal|| <= tol_mm`` as :func:`grid_convergence`, with the
    integrator's tolerances of a single rollout; about one rollout's cost instead of
    ``n_grid**2`` (see :func:`sosdyn.lfd.rollout.final_states`). A start whose integration fails counts as a
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
    final, reasons = final_states(field, starts, horizon, goal, integrator=integrator, rtol=rtol, atol=atol,
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


def grid_convergence_budget(model, demos, n_grid: int = 10, *,
                            budgets: Sequence[tuple[str, int]] = GRID_BUDGETS) -> tuple[GridConvergence | None, str]:
    """:func:`grid_convergence_batched` of a fitted ``model`` (``field``, ``goal_``) under the
    call-budget policy (:func:`sosdyn.lfd.rollout.run_with_budget`: LSODA, then BDF on a budget
    overrun). Returns ``(result, integrator used)``, or ``(None, "budget exceeded")`` when every
    integrator overran."""
    def run(field, integrator):
        return grid_convergence_batched(field, demos, n_grid=n_grid, goal=model.goal_, integrator=integrator)

    try:
        return run_with_budget(run, model.field, budgets)
    except BudgetExceeded:
        return None, "budget exceeded"

"""Rollouts of autonomous vector fields ``xdot = f(x; goal)`` with pushes and goal changes.

The ODE is integrated piecewise between event times with an adaptive, stiffness-switching
solver (``scipy.integrate.solve_ivp``, LSODA by default); fixed-step schemes blow up on the
cubic fields that SOS models produce. Events are right-continuous: the sample at an event
time already shows the pushed state / the new goal.

Size: the output grid has round(duration / dt) + 1 samples; it is checked against
``max_rollout_steps`` and its arrays against ``max_bytes`` (:mod:`sosdyn.limits`) before
anything is allocated. Blow-ups: a trajectory whose state or velocity stops being finite
raises :class:`~sosdyn.errors.SolverError` (status "solver_error", with the time and the
last state); a rollout never returns NaN or inf.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from sosdyn.errors import InputError, SolverError
from sosdyn.limits import check_bytes, check_count

Field = Callable[[np.ndarray, np.ndarray], np.ndarray]  # field(X (m, n), goal (n,)) -> Xdot (m, n)

_METHODS = ("LSODA", "Radau", "BDF", "RK45", "DOP853", "RK23")
_SOLVER_HINT = "a smaller dt or tighter rtol/atol, method='Radau' for stiff fields, or check the model"
_SIZE_HINT = "a larger dt or a shorter duration"


@dataclass
class Trajectory:
    """A rollout sampled on a uniform grid.

    ``t`` (T,) s from 0 to the duration; ``pos`` (T, n); ``goal_history`` (T, n) the goal in
    effect at each sample; ``events``: one dict per applied event, in time order, with keys
    ``kind`` ("push" or "goal_change"), ``time`` and ``before`` / ``after`` (the state for
    a push, the goal for a goal change).
    """

    t: np.ndarray
    pos: np.ndarray
    goal_history: np.ndarray
    events: list[dict] = field(default_factory=list)


def _vector(value, n: int | None, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be a numeric vector ({exc}).") from exc
    if arr.ndim != 1 or (n is not None and arr.shape != (n,)):
        expected = "a 1-D vector" if n is None else f"shape ({n},)"
        raise InputError(f"{what} has shape {arr.shape}; expected {expected}.")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what} contains NaN or inf: {arr}.")
    return arr


def _positive(value, what: str) -> float:
    real = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    if not real or not 0 < value < np.inf:
        raise InputError(f"{what} must be a finite number > 0 (not a bool, not None), got {value!r}.")
    return float(value)


def check_rollout_size(duration: float, dt: float, dim: int, starts: int = 1) -> int:
    """Samples per rollout, round(duration / dt) + 1, after checking it against the limits.

    Counted: ``starts`` rollouts of that many samples against ``max_rollout_steps``; their
    arrays -- time grid and solver output times (2 per sample), positions, goal history and
    solver output ((3 dim) per sample), 8 bytes each -- against ``max_bytes``. Raises
    :class:`~sosdyn.errors.ResourceLimitError` before anything is allocated.
    """
    samples = duration / dt + 1.0          # a float: inf when the ratio overflows, no int overflow
    times = f" x {starts} starts" if starts > 1 else ""
    what = f"the rollout grid (duration {duration:g} s / dt {dt:g} s{times})"
    check_count(samples * starts, "max_rollout_steps", f"{what} sample count", _SIZE_HINT)
    check_bytes(samples * starts * (3 * dim + 2) * 8.0, f"{what} arrays", _SIZE_HINT)
    return int(round(duration / dt)) + 1


def _events(items, n: int, duration: float, kind: str) -> list[tuple[float, str, np.ndarray]]:
    """Validate ``[(time, vector)]`` into ``[(time, kind, vector)]``."""
    if isinstance(items, (str, bytes, dict)) or not hasattr(items, "__iter__"):
        raise InputError(f"{kind} events must be a list of pairs (time, vector), got {type(items).__name__}.")
    out = []
    for i, item in enumerate(items):
        try:
            time, vector = item
        except (TypeError, ValueError) as exc:
            raise InputError(f"{kind} {i} must be a pair (time, vector), got {item!r}.") from exc
        is_number = isinstance(time, (int, float, np.number)) and not isinstance(time, bool)
        if not is_number or not 0 <= time <= duration:
            raise InputError(f"{kind} {i} time {time!r} is not inside [0, duration = {duration:g}].")
        out.append((float(time), kind, _vector(vector, n, f"{kind} {i} vector")))
    return out


def _ode(fld: Field, goal: np.ndarray, n: int):
    """``rhs(t, y)`` for solve_ivp (``y`` (n,) or (n, k)), checking the field's output."""

    def rhs(t, y):
        X = np.atleast_2d(y.T)
        if not np.all(np.isfinite(X)):
            raise SolverError(f"The trajectory blew up: the state is not finite at t = {t:g}.",
                              status="solver_error", hint=_SOLVER_HINT)
        Xdot = np.asarray(fld(X, goal), dtype=float)
        if Xdot.shape != X.shape:
            raise InputError(f"The field returned shape {Xdot.shape} for X of shape {X.shape}; "
                             f"it must return (m, {n}).")
        if not np.all(np.isfinite(Xdot)):
            raise SolverError(f"The field returned NaN/inf at t = {t:g}, x = {X[0]} (the trajectory "
                              "blew up or left the range where the field is finite).",
                              status="solver_error", hint=_SOLVER_HINT)
        return Xdot.T.reshape(y.shape)

    return rhs


def rollout(field: Field, x0, *, duration: float, dt: float, goal, perturbations=(), goal_changes=(),
            rtol: float = 1e-6, atol: float = 1e-8, method: str = "LSODA") -> Trajectory:
    """Integrate ``xdot = field(x, goal)`` from ``x0`` for ``duration`` seconds.

    The output grid is ``linspace(0, duration, round(duration / dt) + 1)``: step ``dt`` up to
    rounding, ending exactly at ``duration``; ``duration`` and ``dt`` are finite numbers > 0
    (numpy scalars accepted, bools refused; dt = 0 is an error, never replaced), and the grid
    is checked by :func:`check_rollout_size` first. ``perturbations``: pairs ``(time, dx)``, at
    ``time`` the state jumps ``x -> x + dx``; ``goal_changes``: pairs ``(time, new_goal)``,
    from ``time`` on the field uses ``new_goal``. Times must lie in [0, duration]; events at
    the same time are applied in the order goal changes, then pushes. Raises
    :class:`InputError` for bad inputs, :class:`~sosdyn.errors.ResourceLimitError` for a grid
    over the limits, and :class:`SolverError` (status "solver_error") if the integrator fails
    or the state or the field stops being finite (no NaN is ever returned).
    """
    if not callable(field):
        raise InputError("field must be callable field(X (m, n), goal (n,)) -> (m, n), "
                         f"got {type(field).__name__}.")
    x = _vector(x0, None, "x0")
    n = len(x)
    g = _vector(goal, n, "goal")
    duration, dt = _positive(duration, "duration"), _positive(dt, "dt")
    rtol, atol = _positive(rtol, "rtol"), _positive(atol, "atol")
    if method not in _METHODS:
        raise InputError(f"method must be one of {', '.join(_METHODS)}, got {method!r}.")
    if dt > duration:
        raise InputError(f"dt = {dt:g} is larger than duration = {duration:g}. "
                         "Try: a smaller dt or a longer duration.")
    events = _events(goal_changes, n, duration, "goal_change") + _events(perturbations, n, duration, "push")
    events.sort(key=lambda e: e[0])  # stable: goal changes before pushes at equal times
    grid = np.linspace(0.0, duration, check_rollout_size(duration, dt, n))
    pos, goals, log = np.empty((len(grid), n)), np.empty((len(grid), n)), []
    starts = sorted({0.0, *(time for time, _, _ in events)})
    ends = starts[1:] + [duration]
    for start, end in zip(starts, ends):
        for time, kind, vector in (e for e in events if e[0] == start):
            if kind == "push":
                with np.errstate(over="ignore"):
                    before, x = x, x + vector
                after = x
            else:
                before, g = g, vector
                after = g
            log.append({"kind": kind, "time": time, "before": before.copy(), "after": after.copy()})
        if not np.all(np.isfinite(x)):
            raise SolverError(f"The state is not finite at t = {start:g} after the push: {x}.",
                              status="solver_error", hint="smaller pushes: x + dx overflows float")
        mask = (grid >= start) & ((grid < end) | ((end == duration) & (grid == duration)))
        if end > start:
            t_eval = np.union1d(grid[mask], [end])  # grid[mask] are its first entries
            with np.errstate(over="ignore", invalid="ignore"):
                sol = solve_ivp(_ode(field, g, n), (start, end), x, method=method, t_eval=t_eval,
                                rtol=rtol, atol=atol, vectorized=True)
            if not sol.success or sol.y.shape[1] != len(t_eval) or not np.all(np.isfinite(sol.y)):
                raise SolverError(f"Integration failed in t = [{start:g}, {end:g}] from x = {x}: "
                                  f"{sol.message}", status="solver_error", hint=_SOLVER_HINT)
            pos[mask] = sol.y.T[:np.count_nonzero(mask)]
            x = sol.y[:, -1]
        else:
            pos[mask] = x
        goals[mask] = g
    return Trajectory(grid, pos, goals, log)

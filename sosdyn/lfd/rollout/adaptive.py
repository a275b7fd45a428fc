"""Adaptive integration (``scipy.integrate.solve_ivp``): rollouts with events, batched final states.

Fixed-step schemes blow up on the cubic fields that SOS models produce, so both functions use
a stiffness-aware adaptive solver (LSODA by default). :func:`rollout`'s tolerances are relative
to the motion's scale s (the model's ``scale_``, or the distance from the start to the goal):
rtol 1e-6, atol ATOL_REL s = 1e-9 s, so the same motion in metres, millimetres or nanometres is
integrated with the same relative accuracy; its work is bounded by ``max_rollout_calls`` and
``max_rollout_seconds`` (:mod:`sosdyn.limits`, :class:`~sosdyn.errors.WorkLimitError`).
:func:`final_states` uses rtol 1e-6 and atol 1e-8 (data units).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.sparse import block_diag

from sosdyn.errors import InputError, SolverError
from sosdyn.lfd.rollout.events import (Field, Trajectory, WorkMeter, as_positive, as_vector,
                                       check_rollout_size, parse_events)

INTEGRATORS = ("LSODA", "Radau", "BDF", "RK45", "DOP853", "RK23")   # solve_ivp methods for rollout
BATCH_INTEGRATORS = ("LSODA", "BDF", "Radau")                        # those final_states supports
_SOLVER_HINT = "a smaller dt or tighter rtol/atol, integrator='Radau' for stiff fields, or check the model"
ATOL_REL = 1e-9             # a rollout's absolute tolerance, relative to the motion's scale


def motion_scale(x0: np.ndarray, goal: np.ndarray, events) -> float:
    """The scale of a rollout when the model gives none: the largest of |x0 - goal|_inf, every push
    |dx|_inf and every goal change |g' - goal|_inf (1.0 when all are 0: the state then stays put)."""
    moves = [np.abs(x0 - goal).max()] + [np.abs(v - (goal if kind == "goal_change" else 0.0)).max()
                                         for _, kind, v in events]
    return float(max(moves)) or 1.0


def _ode(fld: Field, goal: np.ndarray, n: int, meter: WorkMeter | None = None):
    """``rhs(t, y)`` for solve_ivp (``y`` (n,) or (n, k)), checking the field's output and counting
    its work on ``meter``."""

    def rhs(t, y):
        X = np.atleast_2d(y.T)
        if meter is not None:
            meter.tick(t, X, goal)
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
        if meter is not None:
            meter.seen(X[0], Xdot[0], goal)
        return Xdot.T.reshape(y.shape)

    return rhs


def rollout(field: Field, x0, *, duration: float, dt: float, goal, perturbations=(), goal_changes=(),
            rtol: float = 1e-6, atol: float | None = None, scale: float | None = None,
            integrator: str = "LSODA") -> Trajectory:
    """Integrate ``xdot = field(x, goal)`` from ``x0`` for ``duration`` seconds.

    The output grid is ``linspace(0, duration, round(duration / dt) + 1)``: step ``dt`` up to
    rounding, ending exactly at ``duration``; ``duration`` and ``dt`` are finite numbers > 0
    (numpy scalars accepted, bools refused; dt = 0 is an error, never replaced), and the grid
    is checked by :func:`check_rollout_size` first. ``perturbations``: pairs ``(time, dx)``, at
    ``time`` the state jumps ``x -> x + dx``; ``goal_changes``: pairs ``(time, new_goal)``,
    from ``time`` on the field uses ``new_goal`` (:func:`parse_events`). The ODE is integrated
    piecewise between event times with ``solve_ivp(method=integrator)``; events are
    right-continuous (the sample at an event time already shows it). ``atol`` None means
    ATOL_REL * ``scale``, the motion's scale (None: :func:`motion_scale`), so the accuracy
    relative to the motion does not depend on the units. Raises
    :class:`InputError` for bad inputs, :class:`~sosdyn.errors.ResourceLimitError` for a grid
    over the limits, :class:`~sosdyn.errors.WorkLimitError` (a SolverError saying how far it got)
    after ``max_rollout_calls`` field calls or ``max_rollout_seconds``, and :class:`SolverError`
    (status "solver_error") if the integrator fails or the state or the field stops being finite
    (no NaN is ever returned).
    """
    if not callable(field):
        raise InputError("field must be callable field(X (m, n), goal (n,)) -> (m, n), "
                         f"got {type(field).__name__}.")
    x = as_vector(x0, None, "x0")
    n = len(x)
    g = as_vector(goal, n, "goal")
    duration, dt = as_positive(duration, "duration"), as_positive(dt, "dt")
    rtol = as_positive(rtol, "rtol")
    if integrator not in INTEGRATORS:
        raise InputError(f"integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}.")
    if dt > duration:
        raise InputError(f"dt = {dt:g} is larger than duration = {duration:g}. "
                         "Try: a smaller dt or a longer duration.")
    events = parse_events(perturbations, goal_changes, n, duration)
    if atol is None:
        atol = ATOL_REL * (motion_scale(x, g, events) if scale is None else as_positive(scale, "scale"))
    atol = as_positive(atol, "atol")
    grid = np.linspace(0.0, duration, check_rollout_size(duration, dt, n))
    meter = WorkMeter(duration)
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
                sol = solve_ivp(_ode(field, g, n, meter), (start, end), x, method=integrator, t_eval=t_eval,
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


def _integrate_batch(field: Field, X0: np.ndarray, horizon: float, goal: np.ndarray, *, integrator: str,
                     rtol: float, atol: float, escape: float) -> np.ndarray:
    """Final states (m, n) of ``xdot = field(x, goal)`` from all rows of ``X0`` at once.

    The starts are stacked into one ODE ``y = X.ravel()`` (start-major, so its Jacobian is
    block diagonal with n x n blocks). LSODA is told the band (``lband = uband = n - 1``), so
    a finite-difference Jacobian costs 2n - 1 field calls, not m n; BDF/Radau get the block
    sparsity pattern. LSODA's error test uses the weighted max-norm, so every start is held
    to ``rtol``/``atol`` as in a rollout of its own. Starts farther than ``escape`` from the
    goal are frozen there (their derivative set to 0): they have diverged, and integrating
    their exponential growth would only shrink everybody's steps. Raises SolverError on failure.
    """
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

    if integrator == "LSODA":
        options = {"lband": n - 1, "uband": n - 1}
    else:
        options = {"jac_sparsity": block_diag([np.ones((n, n))] * m, format="csc")}
    with np.errstate(over="ignore", invalid="ignore"):
        sol = solve_ivp(rhs, (0.0, horizon), X0.ravel(), method=integrator, t_eval=[horizon],
                        rtol=rtol, atol=atol, **options)
    if not sol.success or sol.y.shape[1] != 1 or not np.all(np.isfinite(sol.y)):
        raise SolverError(f"Integration failed: {sol.message}", status="solver_error")
    return sol.y[:, -1].reshape(m, n)


def final_states(field: Field, starts, horizon: float, goal, *, integrator: str = "LSODA",
                 rtol: float = 1e-6, atol: float = 1e-8,
                 escape: float = np.inf) -> tuple[np.ndarray, list[str | None]]:
    """``x(horizon)`` of ``xdot = field(x, goal)`` from every row of ``starts`` (m, n), batched.

    All starts are integrated as one ODE (block-diagonal Jacobian, see the source of
    ``_integrate_batch``); if that fails (a start diverges, the field returns NaN), the batch
    is split in halves recursively, so only the failing starts are lost. Returns the final
    states (inf rows for failures) and, per start, None or the failure reason. Starts
    farther than ``escape`` from the goal are frozen there (they have diverged) and reported
    with a reason starting "diverged". ``integrator``: one of :data:`BATCH_INTEGRATORS`.
    """
    X0 = np.atleast_2d(np.asarray(starts, dtype=float))
    goal = np.asarray(goal, dtype=float)
    if integrator not in BATCH_INTEGRATORS:
        raise InputError(f"integrator must be one of {BATCH_INTEGRATORS}, got {integrator!r}.")
    out = np.full(X0.shape, np.inf)
    reasons: list[str | None] = [None] * len(X0)

    def solve(idx):
        try:
            out[idx] = _integrate_batch(field, X0[idx], float(horizon), goal, integrator=integrator,
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

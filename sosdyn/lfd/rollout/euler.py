"""Explicit Euler from many starts at once, stopped when every start has come to rest.

The integrator of the LPV-DS / ds-opt evaluation protocol (``Simulation.m``); the protocol's
constants live in :mod:`sosdyn.evaluation.dsopt`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.limits import check_bytes, check_count


def euler_until_rest(field: Callable[[np.ndarray], np.ndarray], starts, *, dt: float, max_steps: int,
                     vel_tol: float, window: int) -> list[np.ndarray]:
    """Explicit-Euler trajectories from all rows of ``starts`` (m, n) at once.

    ``v_i = field(X_i)`` (one call for all m starts), ``X_{i+1} = X_i + dt v_i``, i = 1, 2, ...
    Stops at the first i >= ``window`` with ``|v_j[s, c]| < vel_tol`` for every start s,
    component c and j = i-window+1..i, or at i = ``max_steps`` - 1. Returns m arrays (i, n):
    x_1..x_i of each start (the last update, X_{i+1}, is dropped), all of length i.

    Raises InputError for bad arguments or a field returning another shape, SolverError if a
    state or a velocity becomes NaN/inf (the trajectory diverged).
    """
    X = np.array(starts, dtype=float, ndmin=2)
    (out,) = euler_blocks_until_rest(lambda X, blocks: field(X), X, 1, dt=dt, max_steps=max_steps,
                                     vel_tol=vel_tol, window=window)
    if isinstance(out, SolverError):
        raise out
    return out


def euler_blocks_until_rest(field: Callable[[np.ndarray, list], np.ndarray], starts, blocks: int, *, dt: float,
                            max_steps: int, vel_tol: float, window: int) -> list:
    """:func:`euler_until_rest` for ``blocks`` independent systems at once: the rows of ``starts``
    (m, n) are ``blocks`` equal consecutive blocks, each with its own stop rule (its own rows'
    velocities) and length. ``field(X, live)`` gets the rows of the blocks ``live`` (their indices,
    increasing; the blocks that have neither stopped nor diverged) stacked in that order. Returns,
    per block, its trajectories (as :func:`euler_until_rest`) or the SolverError of its divergence.
    """
    X = np.array(starts, dtype=float, ndmin=2)
    if X.ndim != 2 or not np.all(np.isfinite(X)):
        raise InputError(f"starts must be a finite array (m, n), got shape {X.shape}.")
    for name, value, lo in (("max_steps", max_steps, 2), ("window", window, 1), ("blocks", blocks, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise InputError(f"{name} must be an integer >= {lo}, got {value!r}.")
    for name, value in (("dt", dt), ("vel_tol", vel_tol)):
        if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive number, got {value!r}.")
    m, n = X.shape
    if m % blocks:
        raise InputError(f"{m} starts do not split into {blocks} equal blocks.")
    check_count(max_steps * (m // blocks), "max_rollout_steps",     # per system: the work of one reproduction
                f"An Euler reproduction of {m // blocks} starts x max_steps", "lower max_steps")
    check_bytes(8.0 * max_steps * m * n, "The Euler reproduction's trajectory array", "lower max_steps")
    size = m // blocks
    out = np.empty((max(max_steps - 1, window), m, n))
    done: list = [None] * blocks
    quiet, i = [0] * blocks, 0                    # steps in a row with every |v| < vel_tol (per block); step
    rows_of = {}                                  # the live blocks' rows, by their number (the set only shrinks)
    while True:
        i += 1
        live = [b for b in range(blocks) if done[b] is None]
        if len(live) not in rows_of:              # all blocks live: a slice
            rows_of[len(live)] = slice(None) if len(live) == blocks else \
                np.concatenate([np.arange(b * size, (b + 1) * size) for b in live])
        rows = rows_of[len(live)]
        out[i - 1, rows] = X[rows]
        V = np.asarray(field(X[rows].copy() if len(live) == blocks else X[rows], live), dtype=float)
        if V.shape != (len(live) * size, n):
            raise InputError(f"The field returned shape {V.shape} for X of shape {(len(live) * size, n)}; "
                             "expected the same shape.")
        Vb = V.reshape(len(live), size, n)
        finite = np.isfinite(Vb).all(axis=(1, 2)).tolist()
        calm = (np.abs(Vb) < vel_tol).all(axis=(1, 2)).tolist()
        for k, b in enumerate(live):
            if not finite[k]:
                bad = int(np.flatnonzero(~np.isfinite(Vb[k]).all(axis=1))[0])
                done[b] = SolverError(f"The reproduction from start {bad} diverged: the field returned NaN/inf "
                                      f"at step {i}.", hint="check the model's stability, or lower dt.")
                continue
            quiet[b] = quiet[b] + 1 if calm[k] else 0
            if i >= window and (quiet[b] >= window or i >= max_steps - 1):
                done[b] = [out[:i, s].copy() for s in range(b * size, (b + 1) * size)]
        with np.errstate(over="ignore", invalid="ignore"):
            X[rows] = X[rows] + dt * V
        finite = np.isfinite(X.reshape(blocks, size, n)).all(axis=(1, 2)).tolist()
        for b in range(blocks):
            if done[b] is None and not finite[b]:
                bad = int(np.flatnonzero(~np.isfinite(X[b * size:(b + 1) * size]).all(axis=1))[0])
                done[b] = SolverError(f"The reproduction from start {bad} diverged: its state is NaN/inf at "
                                      f"step {i + 1}.", hint="check the model's stability, or lower dt.")
        if all(d is not None for d in done):
            return done


def euler_arrival_times(field: Callable[[np.ndarray, np.ndarray], np.ndarray], starts, goal, radius: float,
                        deadlines, *, dt: float) -> np.ndarray:
    """First arrival times of explicit-Euler trajectories from the rows of ``starts`` (m, n) at once:
    x_0 = starts[s], x_{i+1} = x_i + dt v_i with ``v = field(X, rows)`` (X the states of the rows
    ``rows`` still running, in increasing order). Returns per start the first i dt with
    |x_i - goal| <= ``radius``, or inf when there is none with i dt <= ``deadlines[s]`` or the state
    stops being finite. A start stops once it has arrived or is overdue: only first arrivals are
    computed, so nothing of a trajectory is stored (memory O(m)) and no step runs past the last one
    that can still decide an arrival."""
    X = np.array(starts, dtype=float, ndmin=2)
    goal, deadlines = np.asarray(goal, dtype=float), np.broadcast_to(np.asarray(deadlines, dtype=float), len(X))
    if X.ndim != 2 or not np.all(np.isfinite(X)) or goal.shape != X.shape[1:]:
        raise InputError(f"starts must be a finite array (m, n) and goal a vector (n,), got shapes {X.shape} "
                         f"and {goal.shape}.")
    for name, value in (("dt", dt), ("radius", radius)):
        if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive number, got {value!r}.")
    out = np.full(len(X), np.inf)
    live, i = np.arange(len(X)), 0
    while live.size:
        Xl = X[live]
        arrived = np.linalg.norm(Xl - goal, axis=1) <= radius
        out[live[arrived]] = i * dt
        live = live[~arrived & (i * dt < deadlines[live]) & np.isfinite(Xl).all(axis=1)]
        if live.size:
            with np.errstate(over="ignore", invalid="ignore"):
                X[live] = X[live] + dt * np.asarray(field(X[live], live), dtype=float)
        i += 1
    return out


def semi_implicit_euler(acceleration: Callable[[np.ndarray, np.ndarray], np.ndarray], X0, V0, *, dt: float,
                        steps: int) -> np.ndarray:
    """Second-order trajectories from all rows of (X0, V0) (m, n) at once, by semi-implicit
    (symplectic) Euler: v_{i+1} = v_i + dt a(x_i, v_i), x_{i+1} = x_i + dt v_{i+1}. Unlike explicit
    Euler it adds no energy to an undamped oscillator (explicit Euler multiplies its amplitude by
    sqrt(1 + (w dt)^2) per step). Returns the positions (steps + 1, m, n), x_0 first; SolverError
    if a state stops being finite."""
    X, V = np.array(X0, dtype=float, ndmin=2), np.array(V0, dtype=float, ndmin=2)
    check_count(float(steps + 1) * X.shape[0], "max_rollout_steps", "semi-implicit Euler steps x starts")
    check_bytes(8.0 * (steps + 1) * X.size, "semi-implicit Euler positions", "a larger dt or fewer steps")
    out = np.empty((steps + 1,) + X.shape)
    out[0] = X
    with np.errstate(over="ignore", invalid="ignore"):
        for i in range(steps):
            V = V + dt * acceleration(X, V)
            X = X + dt * V
            if not (np.isfinite(X).all() and np.isfinite(V).all()):
                raise SolverError(f"semi-implicit Euler diverged at step {i + 1} (the state is not finite).",
                                  status="solver_error", hint="a smaller dt")
            out[i + 1] = X
    return out

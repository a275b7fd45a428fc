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
    if X.ndim != 2 or not np.all(np.isfinite(X)):
        raise InputError(f"starts must be a finite array (m, n), got shape {X.shape}.")
    for name, value, lo in (("max_steps", max_steps, 2), ("window", window, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise InputError(f"{name} must be an integer >= {lo}, got {value!r}.")
    for name, value in (("dt", dt), ("vel_tol", vel_tol)):
        if not (isinstance(value, (int, float, np.floating)) and np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be a positive number, got {value!r}.")
    m, n = X.shape
    check_count(max_steps * m, "max_rollout_steps", f"An Euler reproduction of {m} starts x max_steps",
                "lower max_steps")
    check_bytes(8.0 * max_steps * m * n, "The Euler reproduction's trajectory array", "lower max_steps")
    out = np.empty((max(max_steps - 1, window), m, n))
    quiet, i = 0, 0                             # steps in a row with every |v| < vel_tol; step
    while True:
        i += 1
        if not np.all(np.isfinite(X)):
            bad = int(np.flatnonzero(~np.isfinite(X).all(axis=1))[0])
            raise SolverError(f"The reproduction from start {bad} diverged: its state is NaN/inf at "
                              f"step {i}.", hint="check the model's stability, or lower dt.")
        out[i - 1] = X
        V = np.asarray(field(X), dtype=float)
        if V.shape != X.shape:
            raise InputError(f"The field returned shape {V.shape} for X of shape {X.shape}; "
                             "expected the same shape.")
        if not np.all(np.isfinite(V)):
            bad = int(np.flatnonzero(~np.isfinite(V).all(axis=1))[0])
            raise SolverError(f"The reproduction from start {bad} diverged: the field returned NaN/inf "
                              f"at step {i}.", hint="check the model's stability, or lower dt.")
        quiet = quiet + 1 if np.all(np.abs(V) < vel_tol) else 0
        if i >= window and (quiet >= window or i >= max_steps - 1):
            return [out[:i, s].copy() for s in range(m)]
        with np.errstate(over="ignore", invalid="ignore"):
            X = X + dt * V

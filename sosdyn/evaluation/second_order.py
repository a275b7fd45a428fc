"""Held-out accuracy of first- and second-order motion models (issue 28): ds-opt's protocol adapted.

A method is a fitted model seen through one callable: a velocity field ``f(X) -> Xdot`` (first
order, ``xdot = f(x)``) or an acceleration field ``a(X, V) -> Vdot`` (second order,
``xddot = a(x, xdot)``); a second-order model with an energy tank (``initial_tank`` and
``derivatives``, :class:`~sosdyn.lfd.model.second_order.SecondOrderCDSP`) is seen through
``(X, V, B) -> (Vdot, Bdot)`` with its tank integrated alongside, full at the start. Nothing else of the
model is used (its goal ``goal_`` and its certificate flag, :func:`certified`, are read when present).

Two data paths, one reproduction and scoring:

* ``"dsopt"`` (clean recorded sets, LASA): :func:`sosdyn.evaluation.dsopt.split` (demos 1-4 train,
  5-7 test, every 2nd sample), no preprocessing, ds-opt's stop rule (|v| < 0.1 L/s for 4 steps,
  at most 3000 steps). First-order results equal :func:`sosdyn.evaluation.dsopt.evaluate_shape`'s.
* ``"realdata"`` (noisy recordings, the crossing set): :func:`sosdyn.evaluation.realdata.prepare`
  (first ceil(4N/7) train, preprocessed; test trimmed of rest only, scored as recorded) and its
  stop rule scaled to the data (:func:`sosdyn.evaluation.realdata.stop_rule`).

Reproduction from each test demo's 20th kept sample x_s, with dt = 0.01 s: first order, ds-opt's
explicit Euler; second order, from (x_s, v_s) with v_s the demo's own velocity there (on
``"realdata"`` the Savitzky-Golay velocity with the training window, :func:`start_states`), by
semi-implicit Euler

    v_{i+1} = v_i + dt a(x_i, v_i),    x_{i+1} = x_i + dt v_{i+1},

written as explicit Euler on z = (x, v) with z' = (v + dt a, a), so the same integrator and stop
rule apply: it stops once every component of both v + dt a and a stayed below vel_tol for the
window (at rest, the acceleration vanishes with the velocity). Scores per test demo
(:func:`sosdyn.evaluation.realdata.test_scores`): DTWD to the whole kept demo (on ``"realdata"``
of the reproduction read at the demo's period, :func:`sosdyn.evaluation.realdata.at_period`, so the
curves compared are sampled alike; on ``"dsopt"`` as integrated, ds-opt's protocol), copy (the
nearest training demo's DTWD to it), arrival / duration, excursion, final error.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation import dsopt, realdata
from sosdyn.lfd.data.preprocess import smooth
from sosdyn.lfd.rollout import euler_until_rest

ORDERS = (1, 2)
DATA_PATHS = ("dsopt", "realdata")


def semi_implicit_until_rest(accel: Callable, X0, V0, *, dt: float, max_steps: int, vel_tol: float,
                        window: int, B0=None) -> list[np.ndarray]:
    """Positions (i, n) of the semi-implicit Euler rollouts (module docstring; the fixed-step
    version is :func:`sosdyn.lfd.rollout.euler.semi_implicit_euler`) from the rows of
    ``X0`` and ``V0`` (m, n), all at once: x_0..x_{i-1}, stopped by
    :func:`sosdyn.lfd.rollout.euler_until_rest`'s rule on z = (x, v). With ``B0`` (m,) the model
    carries a tank: ``accel(X, V, B)`` returns (A, dB/dt) and B takes an explicit Euler step (kept
    >= 0) with each step of (x, v), outside the stop rule (euler_until_rest calls the field once per
    step with every row). InputError for mismatched starts, SolverError when a rollout diverges."""
    X0, V0 = np.array(X0, dtype=float, ndmin=2), np.array(V0, dtype=float, ndmin=2)
    if X0.shape != V0.shape:
        raise InputError(f"start positions {X0.shape} and velocities {V0.shape} must have the same shape (m, n).")
    n = X0.shape[1]
    tank = None if B0 is None else np.array(B0, dtype=float).reshape(len(X0))

    def field(Z):
        if tank is None:
            A = accel(Z[:, :n], Z[:, n:])
        else:
            A, rate = accel(Z[:, :n], Z[:, n:], tank)
            tank[:] = np.maximum(0.0, tank + dt * np.asarray(rate, dtype=float))
        A = np.asarray(A, dtype=float)
        if A.shape != (len(Z), n):
            raise InputError(f"The acceleration field returned shape {A.shape} for X of shape {(len(Z), n)}; "
                             "expected the same shape.")
        return np.hstack([Z[:, n:] + dt * A, A])

    paths = euler_until_rest(field, np.hstack([X0, V0]), dt=dt, max_steps=max_steps, vel_tol=vel_tol,
                             window=window)
    return [p[:, :n] for p in paths]


def start_states(test, window: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(X0, V0), (m, n) each: the 20th kept sample of each test demo and its velocity there, the
    recorded one (``window`` None) or the cubic Savitzky-Golay one over ``window`` samples
    (:func:`sosdyn.lfd.data.preprocess.smooth`; the demo must be uniformly sampled enough for the
    filter's mean step)."""
    X0 = dsopt.start_points(test)
    V0 = np.array([(smooth(d, window) if window else d).vel[dsopt.START_INDEX] for d in test])
    return X0, V0


def prepare(demos, data_path: str, split=None):
    """(train for fitting, train as recorded, test, smoothing window or None, preprocessing lines):
    the module docstring's two data paths; ``split`` = (train, test) 0-based indices replaces
    ds-opt's 1-4 / 5-7 on the ``"dsopt"`` path (e.g. per pattern on LASA's Multi_Models)."""
    if data_path == "dsopt":
        train, test = dsopt.split(demos, *(split or dsopt.SPLITS["standard"]))
        return train, train, test, None, []
    if data_path == "realdata" and split is None:
        fitted, recorded, test, report = realdata.prepare(demos)
        return fitted, recorded, test, report.window, report.lines(getattr(demos, "units", ""))
    raise InputError(f"data_path must be one of {DATA_PATHS} (split: dsopt only), got {data_path!r} with "
                     f"split {split!r}.")


def reproduce(field, order: int, train, test, data_path: str, window: int | None = None):
    """The reproductions of ``test`` (module docstring) by ``field`` of ``order`` 1 or 2 (for 2 also a
    model with a tank, :func:`second_order_field`)."""
    if order not in ORDERS:
        raise InputError(f"order must be 1 or 2, got {order!r}.")
    vel_tol, max_steps = ((dsopt.VEL_TOL, dsopt.MAX_STEPS) if data_path == "dsopt"
                          else realdata.stop_rule(train, test))
    if order == 1:
        return dsopt.euler_reproduce(field, dsopt.start_points(test), vel_tol=vel_tol, max_steps=max_steps)
    X0, V0 = start_states(test, window)
    accel, B0 = second_order_field(field, X0, V0)
    return semi_implicit_until_rest(accel, X0, V0, dt=dsopt.DT, max_steps=max_steps, vel_tol=vel_tol,
                                    window=dsopt.WINDOW, B0=B0)


def second_order_field(model, X0, V0):
    """(the callable, the tanks at the starts or None) through which a second-order ``model`` is
    integrated (module docstring): a model with ``initial_tank`` and ``derivatives`` with its tank,
    else ``model.predict`` (or ``model`` itself when it is a callable a(X, V))."""
    if hasattr(model, "initial_tank") and hasattr(model, "derivatives"):
        goal = model.goal_
        return (lambda X, V, B: model.derivatives(X, V, goal, B)), model.initial_tank(X0, V0)
    return getattr(model, "predict", model), None


def certified(model) -> bool | None:
    """The model's ``certified_``, else its ``certificate_.passed``; None for a model without a
    certificate."""
    if hasattr(model, "certified_"):
        return bool(model.certified_)
    passed = getattr(getattr(model, "certificate_", None), "passed", None)
    return None if passed is None else bool(passed)


def summary(rows: list[dict]) -> dict:
    """Means of DTWD and copy over the test demos, their ratio (inf when copy is exact, 0), and
    the worst excursion, arrival ratio and final error."""
    dtwd_mean, copy_mean = float(np.mean([r["dtwd"] for r in rows])), float(np.mean([r["copy"] for r in rows]))
    return {"dtwd_mean": dtwd_mean, "copy_mean": copy_mean, "ratio": dtwd_mean / copy_mean if copy_mean > 0 else np.inf,
            **{k: max(r[k] for r in rows) for k in ("excursion", "arrival_ratio", "final_error")}}


def evaluate(fit_fn: Callable, demos, order: int, data_path: str, grid=None, split=None) -> dict:
    """The protocol on one set: ``fit_fn(train)`` returns a model whose ``predict`` is the field
    of ``order`` (velocity(X) for 1, acceleration(X, V) for 2). Returns per-test ``tests`` rows,
    :func:`summary`'s means and worsts, ``fit_s``, ``certified`` (:func:`certified`), the
    preprocessing lines (``split``: :func:`prepare`'s), the thinned reproductions (``paths``), and for a
    diverging reproduction ``failure`` (then no scores). ``grid`` (G, n), optional: the field at
    those points (at rest, V = 0, for order 2) is returned as ``grid_field`` (for figures)."""
    train, recorded, test, window, lines = prepare(demos, data_path, split)
    t0 = time.perf_counter()
    model = fit_fn(train)
    fit_s = time.perf_counter() - t0
    goal = np.asarray(getattr(model, "goal_", train.goal), dtype=float)
    out = {"name": getattr(demos, "name", ""), "order": order, "n_train": len(train), "n_test": len(test),
           "fit_s": fit_s, "certified": certified(model), "preprocess": lines,
           "smoothing_window": window, "failure": None}
    if grid is not None:
        G = np.asarray(grid, dtype=float)
        out["grid_field"] = model.predict(G) if order == 1 else model.predict(G, np.zeros_like(G))
    t0 = time.perf_counter()
    try:
        paths = reproduce(model.predict if order == 1 else model, order, recorded, test, data_path, window)
    except SolverError as exc:
        return dict(out, failure=str(exc))
    rows = realdata.test_scores(paths, recorded, test, goal, alike=data_path == "realdata")
    return dict(out, tests=rows, **summary(rows), reproduce_s=time.perf_counter() - t0,
                paths=[realdata.thin(p) for p in paths])


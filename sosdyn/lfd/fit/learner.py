"""The CDSP learner as functions on arrays: (scaled data, mixture, settings) -> fields C, metric W.

Stages (the estimator :class:`~sosdyn.lfd.model.cdsp.CDSP` calls :func:`learn`):

A. linear fields f_k = A_k z under a constant metric P: a dynamics step with M = I, then
   either plain alternation (metric step, dynamics step, ...) or the inner convex
   approximation (ICA step, dynamics step under the new P, ...), until the cost stalls;
B. (field_degree > 1 or a learned metric_degree > 0) stage A's certified (C, P) embedded in
   the larger monomial sets, a dynamics step with the higher-degree terms, and alternation;
C. (refine_gmm) the mixture refined with the metric fixed (:mod:`~sosdyn.lfd.fit.refine`).

Every row of the fit's history (step, cost, solver status and times) goes through a
:class:`History`. The compiled steps live inside :func:`learn`, or, within a
:func:`reuse_steps` block (``CDSP.fit``: its warp candidates and corrective rounds), in a
:class:`StepCache` shared by the fits of that block: a step's SOS terms and Gram matching
depend only on its structure (sizes, monomials, gamma, margins, solver), so a later fit of the
same structure only gives it its own data term (``use_data``). Every solve sets all the step's
weights (and, for the steps that change it per solve, the objective), so a reused step returns
the numbers a fresh one would.
"""
from __future__ import annotations

from collections.abc import Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, fields

import numpy as np

from sosdyn.errors import SolverError, UnverifiedSolutionError
from sosdyn.poly import match_rows, monomial_values
from .contraction import field_exponents, margin_degree, metric_exponents, state_variables
from .gmm import PositionMixture
from .refine import refine_mixture
from .steps import DynamicsStep, ICAStep, LeastSquaresData, MetricStep

LEARNER_HINT = "a smaller gamma, solver_method='alternating', or fewer components"
NO_ROOM = 1e-9              # a metric step margin this small: the alternation is at a fixed point
COST_FLOOR = 1e-12          # the stopping test's relative tolerance never divides by less


@dataclass(frozen=True)
class Settings:
    """The hyper-parameters the learning stages use (a subset of CDSP's, already checked)."""

    field_degree: int
    metric_degree: int
    gamma: float
    metric: str
    solver: str
    solver_method: str
    max_iter: int
    tol: float
    eps: float
    margin: float
    metric_prox: float
    refine_gmm: bool

    @classmethod
    def from_params(cls, params: Mapping) -> Settings:
        return cls(**{f.name: params[f.name] for f in fields(cls)})

    @property
    def learned_metric_degree(self) -> int:
        """Degree of M(z): ``metric_degree`` for a learned metric, 0 for the identity."""
        return self.metric_degree if self.metric == "learned" else 0


class History:
    """The rows of a fit, in order; each is also passed to ``progress`` (if given)."""

    def __init__(self, progress=None):
        self.rows: list = []
        self.progress = progress

    def record(self, step, cost, sol=None, **extra):
        row = {"iteration": len(self.rows), "step": step, "cost": float(cost)}
        if sol is not None:
            row.update(status=sol.status, solve_s=sol.timings["solve"],
                       build_s=sol.timings["build"] + sol.timings["canonicalize"])
            if sol.info.get("iterations") is not None:          # the solver's (interior-point) iterations
                row["iterations"] = int(sol.info["iterations"])
            if "fallback" in sol.info:
                row["fallback"] = sol.info["fallback"]
        row.update(extra)
        self.rows.append(row)
        if self.progress is not None:
            self.progress(row)


class StepCache:
    """Compiled steps by structure key (module docstring): ``step(cls, *args, data=, **kwargs)``."""

    def __init__(self):
        self.steps: dict = {}

    def step(self, cls, *args, data=None, **kwargs):
        """``cls(data, *args, **kwargs)`` (``cls(*args, **kwargs)`` without data), or the step
        compiled earlier from equal arguments and a data term of the same shape, given ``data``."""
        key = (cls, None if data is None else data.shape) + tuple(map(structure, args)) \
            + tuple((k, structure(v)) for k, v in sorted(kwargs.items()))
        if key not in self.steps:
            self.steps[key] = cls(*args, **kwargs) if data is None else cls(data, *args, **kwargs)
        elif data is not None:
            self.steps[key].use_data(data)
        return self.steps[key]


_CACHE: ContextVar = ContextVar("sosdyn_step_cache", default=None)


@contextmanager
def reuse_steps():
    """Within the block, the fits of :func:`learn` (in this thread) share one :class:`StepCache`."""
    token = _CACHE.set(StepCache())
    try:
        yield
    finally:
        _CACHE.reset(token)


def active_step_cache() -> StepCache | None:
    """The :class:`StepCache` of the innermost :func:`reuse_steps` block of this thread, or None."""
    return _CACHE.get()


def compiled(cls, *args, data=None, **kwargs):
    """A step from the active :class:`StepCache` (:func:`reuse_steps`), else a new one."""
    cache = active_step_cache()
    if cache is None:
        return cls(*args, **kwargs) if data is None else cls(data, *args, **kwargs)
    return cache.step(cls, *args, data=data, **kwargs)


def structure(value):
    """A hashable key of a step argument: arrays by dtype, shape and bytes."""
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.str, value.shape, value.tobytes())
    return value


def subsample(X, Xdot, max_samples):
    """Every step-th row, step = ceil(T / max_samples), if there are more than max_samples rows
    (None: all). Returns (X, Xdot, subsampled)."""
    if max_samples is None or X.shape[0] <= max_samples:
        return X, Xdot, False
    step = int(np.ceil(X.shape[0] / max_samples))
    return X[::step], Xdot[::step], True


def least_squares_data(Z, Zdot, mixture: PositionMixture, fexps) -> LeastSquaresData:
    """The data term (18) at the scaled samples for the fields' monomials ``fexps``."""
    return LeastSquaresData(mixture.responsibilities(Z), monomial_values(Z, fexps), Zdot)


def stalled(old: float, new: float, tol: float) -> bool:
    """The stopping test: the cost fell by at most ``tol`` relative to the old cost."""
    return old - new <= tol * max(old, COST_FLOOR)


def cap_note(max_iter: int, change: float, tol: float) -> str:
    """The sentence of a fit stopped by its iteration cap (every family's ``iteration_cap``)."""
    return f"stopped at max_iter={max_iter} with relative change {change:.2e} > tol={tol:g}"


def capped(rows: list[dict], max_iter: int, tol: float) -> str | None:
    """:func:`cap_note` when the history rows of one fit (one warp candidate or corrective round) used
    all ``max_iter`` iterations (ica or metric steps) and the last one still changed the cost by more
    than ``tol`` (:func:`stalled`); None otherwise."""
    iterations = sum(r["step"] in ("ica", "metric") for r in rows)
    costs = [r["cost"] for r in rows if r["step"].startswith("dynamics")]
    if iterations < max_iter or len(costs) < 2 or not rows[-1]["step"].startswith("dynamics"):
        return None
    old, new = costs[-2], costs[-1]
    return None if stalled(old, new, tol) else cap_note(max_iter, (old - new) / max(old, COST_FLOOR), tol)


def embed(coef, exps_from, exps_to):
    """Coefficients over ``exps_from`` (last axis) re-indexed over the larger monomial set ``exps_to``."""
    out = np.zeros(coef.shape[:-1] + (exps_to.shape[0],))
    out[..., match_rows(exps_to, exps_from)] = coef
    return out


def with_learner_hint(exc: SolverError) -> SolverError:
    """The same error, its message prefixed by "CDSP fit failed" and the learner's advice first."""
    hint = LEARNER_HINT if not exc.hint else f"{LEARNER_HINT}; or {exc.hint}"
    message = f"CDSP fit failed: {exc.detail}"
    if isinstance(exc, UnverifiedSolutionError):
        return type(exc)(message, exc.status, hint, exc.report)
    return type(exc)(message, exc.status, hint)


def learn(Z, Zdot, mixture: PositionMixture, s: Settings, history: History):
    """Fields C (K, n, m), metric W (n, n, p) and the mixture (refined if ``s.refine_gmm``),
    from the scaled samples Z, Zdot (T, n). SolverErrors carry the learner's hint."""
    try:
        C, W, dyn = learn_fields(Z, Zdot, mixture, s, history)
        if s.refine_gmm:
            mixture, C = refine_mixture(Z, Zdot, mixture, C, field_exponents(Z.shape[1], s.field_degree),
                                        dyn, history.record)
    except SolverError as exc:
        raise with_learner_hint(exc) from exc
    return C, W, mixture


def learn_fields(Z, Zdot, mixture, s: Settings, history: History):
    """Stages A and B (module docstring): (C, W, the last dynamics step)."""
    n = Z.shape[1]
    lin_exps, const_exps = field_exponents(n, 1), metric_exponents(n, 0)
    C, P, dyn = stage_a(least_squares_data(Z, Zdot, mixture, lin_exps), lin_exps, const_exps, s, history)
    if s.field_degree == 1 and s.learned_metric_degree == 0:
        return C, P[:, :, None], dyn
    fexps, mexps = field_exponents(n, s.field_degree), metric_exponents(n, s.learned_metric_degree)
    data = least_squares_data(Z, Zdot, mixture, fexps)
    C = embed(C, lin_exps, fexps)
    W = embed(P[:, :, None], const_exps, mexps)
    dyn = compiled(DynamicsStep, fexps, mexps, state_variables(n), s.gamma, s.margin, s.solver, data=data)
    C, sol = dyn.solve(W)
    history.record("dynamics (degree %d)" % s.field_degree, data.cost(C), sol)
    if s.learned_metric_degree > 0:
        C, W = alternate(data, dyn, C, W, fexps, mexps, s, history)
    return C, W, dyn


def stage_a(data: LeastSquaresData, fexps, mexps, s: Settings, history: History):
    """Linear fields and a constant metric: (C, P, the dynamics step)."""
    n = data.shape[1]
    vars = state_variables(n)
    dyn = compiled(DynamicsStep, fexps, mexps, vars, s.gamma, s.margin, s.solver,
                   affine_psd=s.solver_method == "ica", data=data)
    W = np.eye(n)[:, :, None]
    C, sol = dyn.solve(W)
    history.record("dynamics (M = I)", data.cost(C), sol)
    if s.metric == "identity":
        return C, np.eye(n), dyn
    if s.solver_method == "alternating":
        C, W = alternate(data, dyn, C, W, fexps, mexps, s, history)
        return C, W[:, :, 0], dyn
    ica = compiled(ICAStep, fexps, vars, s.gamma, s.margin, s.eps, s.solver, data=data)
    P = np.eye(n)
    for _ in range(s.max_iter):
        old = data.cost(C)
        C, P, sol = ica.solve(C, P)
        history.record("ica", data.cost(C), sol)
        C, sol = dyn.solve(P[:, :, None])          # all coefficients under the new metric
        cost = data.cost(C)
        history.record("dynamics", cost, sol)
        if stalled(old, cost, s.tol):
            break
    return C, P, dyn


def alternate(data: LeastSquaresData, dyn: DynamicsStep, C, W, fexps, mexps, s: Settings, history: History):
    """Alternation: metric step (max margin, proximal to the current metric if ``s.metric_prox``)
    then dynamics step, until no progress: (C, W)."""
    K, n, _ = data.shape
    grow = margin_degree(W, mexps, fexps)
    met = compiled(MetricStep, n, K, mexps, fexps, state_variables(n), s.gamma, s.eps, grow_degree=grow,
                   solver=s.solver)
    for _ in range(s.max_iter):
        W_new, t, sol = met.solve(C, W, s.metric_prox)
        history.record("metric", data.cost(C), sol, margin=t)
        if t <= NO_ROOM:
            break
        W, old = W_new, data.cost(C)
        C, sol = dyn.solve(W, margin=0.5 * t, grow_degree=grow)
        cost = data.cost(C)
        history.record("dynamics", cost, sol)
        if stalled(old, cost, s.tol):
            break
    return C, W

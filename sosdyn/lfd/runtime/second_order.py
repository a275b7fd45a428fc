"""A fitted second-order model at run time: the one-state evaluator
(:class:`SecondOrderPredictor`, ``step(x, v, goal=None) -> acceleration``) and the standalone Python
module (:func:`to_python`, numpy only, ``acceleration(X, V, goal=None)``), computing what
:meth:`~sosdyn.lfd.model.second_order.SecondOrderCDSP.predict` computes with every number written out
exactly (``repr`` round-trips):

    e = ((x - g)/s, v T/s),   a = (s / T^2) sum_k h_k(e) C_k e,   h_k: the gating GMM on e,

(:func:`~sosdyn.lfd.fit.second_order.acceleration_at`, the one formula). The certificate does not
involve h, g, s or T, so a moved goal keeps it: the state still converges to (goal, 0). The
generated mixture code is shared with the first-order export (:data:`~.codegen.MIXTURE_PY`,
:data:`~.codegen.RESPONSIBILITIES_PY`). The opening comment is fixed text and numbers only
(:data:`~.codegen.PREAMBLE`); no string from the model reaches the file.
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import NotFittedError
from ..fit.gmm import PositionMixture
from ..fit.second_order import acceleration_at
from .codegen import MIXTURE_PY, PREAMBLE, RESPONSIBILITIES_PY, _literal
from .states import as_state


class SecondOrderPredictor:
    """``pred(x, v, goal=None)`` (also ``pred.step``): the acceleration (n,) at one state (x, v)."""

    def __init__(self, goal: np.ndarray, length: float, time: float, mixture: PositionMixture, C: np.ndarray):
        self.goal, self.length, self.time = np.array(goal, dtype=float), float(length), float(time)
        self.mixture, self.C, self.dim = mixture, np.array(C, dtype=float), len(goal)

    def __call__(self, x, v, goal=None) -> np.ndarray:
        n = self.dim
        g = self.goal if goal is None else as_state(goal, n, "goal")
        X, V = as_state(x, n, "x")[None], as_state(v, n, "v")[None]
        return acceleration_at(X, V, g, self.length, self.time, self.mixture, self.C)[0]

    step = __call__


def to_python(model) -> str:
    """Source of the standalone module of the fitted second-order ``model``."""
    if not hasattr(model, "C_"):
        raise NotFittedError("only a fitted SecondOrderCDSP can be exported. Try: model.fit(demos) or "
                             "sosdyn.load_model(path) first.")
    K, n, _ = model.C_.shape
    mix = model.mixture_
    head = "".join(f"# {line}\n" for line in (
        *PREAMBLE, f"Second order: n = {n} positions, state (x, v), K = {K} components.",
        "a = (s / T^2) sum_k h_k(e) C_k e, e = ((x - goal) / s, v T / s)."))
    return head + f'''"""Standalone evaluator of a second-order CDSP motion: acceleration(X, V, goal=None)."""
import numpy as np

GOAL = np.array({_literal(model.goal_)})
LENGTH = {float(model.length_scale_)!r}    # s
TIME = {float(model.time_scale_)!r}    # T
# the gating mixture h_k(e) on e = ((x - g)/s, v T/s): weights, means, covariances
WEIGHTS = np.array({_literal(mix.weights)})
MEANS = np.array({_literal(mix.means)})
COVARIANCES = np.array({_literal(mix.covariances)})
BOUND = None     # the gating is not tempered
FIELDS = np.array({_literal(model.C_)})     # (K, n, 2n): C_k = [A_k, B_k], scaled units
DIM = GOAL.size
{MIXTURE_PY}

{RESPONSIBILITIES_PY}

def acceleration(X, V, goal=None):
    """Accelerations at positions X and velocities V: shape (m, n) each -> (m, n), or (n,) -> (n,);
    towards ``goal`` (shape (n,); None: GOAL), the motion translated to it."""
    X, V = np.asarray(X, dtype=float), np.asarray(V, dtype=float)
    single = X.ndim == 1
    X, V = (X[None, :], V[None, :]) if single else (X, V)
    if X.ndim != 2 or X.shape[1] != DIM or V.shape != X.shape:
        raise ValueError(f"X and V must both have shape (m, {{DIM}}) or ({{DIM}},), "
                         f"got {{np.shape(X)}}, {{np.shape(V)}}")
    goal = GOAL if goal is None else np.asarray(goal, dtype=float)
    if not (np.isfinite(X).all() and np.isfinite(V).all() and goal.shape == GOAL.shape and np.isfinite(goal).all()):
        raise ValueError("X, V and goal must be finite, goal of shape ({{DIM}},)")
    E = np.hstack([(X - goal) / LENGTH, V * (TIME / LENGTH)])
    with np.errstate(over="ignore", invalid="ignore"):
        A = np.einsum("tk,kij,tj->ti", responsibilities(E), FIELDS, E) * (LENGTH / TIME ** 2)
    if not np.isfinite(A).all():
        raise ValueError("a state is so far from the data that the acceleration overflows float")
    return A[0] if single else A
'''

"""A fitted second-order model at run time: the one-state evaluator
(:class:`SecondOrderPredictor`, ``step(x, v, goal=None) -> acceleration``), the standalone Python
module (:func:`to_python`, numpy only, ``acceleration(X, V, goal=None)``) and the header-only C++17
evaluator (:func:`to_cpp`, ``bool acceleration(const double* x, const double* v, double* a, const
double* goal = nullptr)``, <array> and <cmath> only), computing what
:meth:`~sosdyn.lfd.model.second_order.SecondOrderCDSP.predict` computes with every number written out
exactly (``repr`` round-trips):

    e = ((x - g)/s, v T/s),   a = (s / T^2) sum_k h_k(e) C_k e,   h_k: the gating GMM on e,

(:func:`~sosdyn.lfd.fit.second_order.acceleration_at`, the one formula). The certificate does not
involve h, g, s or T, so a moved goal keeps it: the state still converges to (goal, 0). A tracking
model (``field="tracking"``) carries a tank b: :class:`TankPredictor` keeps it, the Python module has
``derivatives(X, V, tank, goal=None)``, ``initial_tank`` and ``acceleration(X, V, goal=None, tank=None)``
and the C++ header ``initial_tank``, ``acceleration(x, v, a, tank, dt, goal)``, which advances the
tank by dt, and ``acceleration(x, v, a, goal)`` (a full tank, as predict) (:mod:`~sosdyn.lfd.fit.second_order.tank`, :func:`~sosdyn.lfd.fit.second_order.tank.derivatives_at`). The
generated mixture code is shared with the first-order exports (:data:`~.codegen.MIXTURE_PY`,
:data:`~.codegen.RESPONSIBILITIES_PY`, :func:`~.export_cpp.cpp_mixture`). The opening comment is fixed text and numbers only
(:data:`~.codegen.PREAMBLE`); no string from the model reaches the file.
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import NotFittedError
from ..fit.gmm import PositionMixture
from ..fit.second_order import acceleration_at
from ..fit.second_order.tank import TankField, derivatives_at, initial_tank, scaled_states
from .codegen import MIXTURE_PY, PREAMBLE, RESPONSIBILITIES_PY, _flat, _literal, check_namespace, gating_py
from .export_cpp import cpp_mixture
from .second_order_tank import header_prologue, tank_cpp, tank_python
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


class TankPredictor:
    """``pred(x, v, goal=None, dt=None)`` (also ``pred.step``): the acceleration (n,) at (x, v) with the
    predictor's tank level ``tank``, full (beta V(e)) at the first state after construction or
    :meth:`reset`; with ``dt`` (s) the tank is then advanced one explicit Euler step (kept >= 0), as
    a control loop at period dt does."""

    def __init__(self, field: TankField, goal: np.ndarray, length: float, time: float):
        self.field, self.goal, self.length, self.time = field, np.array(goal, dtype=float), float(length), float(time)
        self.dim, self.tank = len(goal), None

    def reset(self) -> None:
        """Start a new motion: the tank fills at the next state."""
        self.tank = None

    def __call__(self, x, v, goal=None, dt=None) -> np.ndarray:
        n = self.dim
        g = self.goal if goal is None else as_state(goal, n, "goal")
        X, V = as_state(x, n, "x")[None], as_state(v, n, "v")[None]
        if self.tank is None:
            self.tank = float(initial_tank(self.field, scaled_states(X, V, g, self.length, self.time))[0])
        A, bdot = derivatives_at(self.field, X, V, g, self.length, self.time, np.array([self.tank]))
        if dt is not None:
            self.tank = max(0.0, self.tank + float(dt) * float(bdot[0]))
        return A[0]

    step = __call__


def _head(model, comment: str) -> str:
    """The generated file's opening comment: :data:`~.codegen.PREAMBLE`, then numbers only."""
    if not hasattr(model, "C_"):
        raise NotFittedError("only a fitted SecondOrderCDSP can be exported. Try: model.fit(demos) or "
                             "sosdyn.load_model(path) first.")
    K, n, _ = model.C_.shape
    if model.tank_ is not None:
        return "".join(f"{comment} {line}\n" for line in (
            *PREAMBLE, f"Second order, tracking: n = {n} positions, state (x, v, tank), {len(model.tank_.samples)} "
            "tracked samples; positions in UNITS.", "a = the tracking field filtered by the energy tank, "
            "e = ((x - goal) / s, v T / s)."))
    return "".join(f"{comment} {line}\n" for line in (
        *PREAMBLE, f"Second order: n = {n} positions, state (x, v), K = {K} components; positions in UNITS.",
        "a = (s / T^2) sum_k h_k(e) C_k e, e = ((x - goal) / s, v T / s)."))


def to_python(model) -> str:
    """Source of the standalone module of the fitted second-order ``model``."""
    head = _head(model, "#")
    if model.tank_ is not None:
        return head + tank_python(model)
    mix = model.mixture_
    return head + f'''"""Standalone evaluator of a second-order CDSP motion: acceleration(X, V, goal=None)."""
import numpy as np

UNITS = {ascii(str(model.units_))}
COLUMNS = {ascii(tuple(map(str, model.names())))}     # the names of the position coordinates
GOAL = np.array({_literal(model.goal_)})
LENGTH = {float(model.length_scale_)!r}    # s
TIME = {float(model.time_scale_)!r}    # T
# the gating mixture h_k(e) on e = ((x - g)/s, v T/s): weights, means, covariances
WEIGHTS = np.array({_literal(mix.weights)})
MEANS = np.array({_literal(mix.means)})
COVARIANCES = np.array({_literal(mix.covariances)})
{gating_py(mix)}FIELDS = np.array({_literal(model.C_)})     # (K, n, 2n): C_k = [A_k, B_k], scaled units
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
        raise ValueError(f"X, V and goal must be finite, goal of shape ({{DIM}},)")
    E = np.hstack([(X - goal) / LENGTH, V * (TIME / LENGTH)])
    with np.errstate(over="ignore", invalid="ignore"):
        A = np.einsum("tk,kij,tj->ti", responsibilities(E), FIELDS, E) * (LENGTH / TIME ** 2)
    if not np.isfinite(A).all():
        raise ValueError("a state is so far from the data that the acceleration overflows float")
    return A[0] if single else A
'''


def to_cpp(model, namespace: str = "second_order_model") -> str:
    """Source of the header-only C++17 evaluator of the fitted second-order ``model`` in ``namespace``:
    ``bool acceleration(const double* x, const double* v, double* a, const double* goal = nullptr)``
    for one state (x, v) of P doubles each (``goal``: P doubles, nullptr = the model's); false when
    the acceleration is not finite (a state or goal not finite, or so far away that it overflows)."""
    head = _head(model, "//")
    namespace = check_namespace(namespace, "second_order_model")
    if model.tank_ is not None:
        return head + tank_cpp(model, namespace)
    K = model.C_.shape[0]
    return head + header_prologue(model, namespace, ": the gating's dimension") + f"""constexpr int K = {K};   // mixture components
// fields[(k * P + i) * N + j] = C[k, i, j], C_k = [A_k, B_k] in scaled units
constexpr std::array<double, K * P * N> fields = {{{_flat(model.C_)}}};
{cpp_mixture(model.mixture_)}
// a = (s / T^2) sum_k h_k(e) C_k e, e = ((x - g) / s, v T / s), g = goal (P doubles) or, for nullptr,
// the model's; false if a is not finite.
inline bool acceleration(const double* x, const double* v, double* a, const double* goal = nullptr) {{
  const double* g = goal != nullptr ? goal : {namespace}::goal.data();
  std::array<double, N> e{{}};
  for (int i = 0; i < P; ++i) {{
    if (!std::isfinite(x[i]) || !std::isfinite(v[i]) || !std::isfinite(g[i])) return false;
    e[i] = (x[i] - g[i]) / length_scale;
    e[P + i] = v[i] * (time_scale / length_scale);
  }}
  std::array<double, K> h{{}};
  responsibilities(e.data(), h.data());
  bool finite = true;
  for (int i = 0; i < P; ++i) {{
    double s = 0.0;
    for (int k = 0; k < K; ++k) {{
      double f = 0.0;
      for (int j = 0; j < N; ++j) f += fields[(k * P + i) * N + j] * e[j];
      s += h[k] * f;
    }}
    a[i] = s * (length_scale / (time_scale * time_scale));
    finite = finite && std::isfinite(a[i]);
  }}
  return finite;
}}

}}  // namespace {namespace}
"""

"""Code generation for a tracking second-order model (``field="tracking"``): the standalone Python
module (:func:`tank_python`, numpy only) and the header-only C++17 evaluator (:func:`tank_cpp`, <array>
and <cmath> only), computing what :func:`~sosdyn.lfd.fit.second_order.tank.derivatives_at` computes
with every number written out exactly (``repr`` round-trips):

    e = ((x - g)/s, v T/s),   a*(e) = (1 - phi(e)) sum_i w_i(e) target_i - w^2 e_x - 2 w e_v   (the tracking field),
    V = e^T M e,  dV(a) = 2 (M e)_x . e_v + 2 (M e)_v . a,  a_0 = C_0 e  (the witness),
    a = a* if dV(a*) <= -2 gamma' V + rho b, else a_0 + lam (a* - a_0) with dV = -2 gamma' V + rho b,
    db/dt' = -max(0, dV(a) + 2 gamma' V) - 2 gamma' b,   b(0) = beta V(e(0)),

then a (s / T^2) and db/dt = (db/dt') / T (:mod:`~sosdyn.lfd.fit.second_order.tank`). The header's
``acceleration`` also advances the caller's tank by one explicit Euler step of ``dt`` seconds.
"""
from __future__ import annotations

from ..fit.second_order.tank import TANK_RATE
from ..fit.second_order.tracking import GOAL_RADIUS, tracking_targets
from .codegen import _flat, _literal, cpp_string, cpp_strings


def _numbers(model) -> dict:
    """The model's numbers as the generated code names them."""
    f = model.tank_
    return {"SAMPLES": f.samples, "TARGETS": tracking_targets(f.samples, f.accelerations, f.omega),
            "INV_WIDTHS": f.inv_widths, "OMEGA": float(f.omega), "METRIC": f.M, "WITNESS": f.C0,
            "GAMMA": float(f.gamma), "BETA": float(f.beta), "RATE": float(TANK_RATE), "RADIUS": float(GOAL_RADIUS)}


def tank_python(model) -> str:
    """The body (after the opening comment) of the standalone Python module of a tracking ``model``."""
    num = _numbers(model)
    arrays = "\n".join(f"{k} = np.array({_literal(num[k])})" for k in ("SAMPLES", "TARGETS", "INV_WIDTHS", "METRIC",
                                                                        "WITNESS"))
    return f'''"""Standalone evaluator of a second-order CDSP tracking motion with an energy tank:
derivatives(X, V, tank, goal=None), initial_tank(X, V, goal=None), acceleration(X, V, goal=None, tank=None)."""
import numpy as np

UNITS = {ascii(str(model.units_))}
COLUMNS = {ascii(tuple(map(str, model.names())))}     # the names of the position coordinates
GOAL = np.array({_literal(model.goal_)})
LENGTH = {float(model.length_scale_)!r}    # s
TIME = {float(model.time_scale_)!r}    # T
OMEGA = {num["OMEGA"]!r}    # w: the pull back to the samples (scaled units)
RADIUS = {num["RADIUS"]!r}    # r: near the goal the field fades to the landing -w^2 e_x - 2 w e_v
GAMMA = {num["GAMMA"]!r}    # gamma' = gamma T
BETA = {num["BETA"]!r}    # b(0) = BETA V(e(0))
RATE = {num["RATE"]!r}    # rho: the tank pays at most rho b per unit of t'
# tracked samples e_i (N, 2n), target_i = a_i + w^2 x_i + 2 w v_i (N, n), 1 / kernel widths (2n,),
# the metric M (2n, 2n) and the witness C_0 (n, 2n), all in scaled units
{arrays}
DIM = GOAL.size
CHUNK = 128


def _states(X, V, goal):
    X, V = np.asarray(X, dtype=float), np.asarray(V, dtype=float)
    single = X.ndim == 1
    X, V = (X[None, :], V[None, :]) if single else (X, V)
    if X.ndim != 2 or X.shape[1] != DIM or V.shape != X.shape:
        raise ValueError(f"X and V must both have shape (m, {{DIM}}) or ({{DIM}},), got {{np.shape(X)}}, {{np.shape(V)}}")
    goal = GOAL if goal is None else np.asarray(goal, dtype=float)
    if not (np.isfinite(X).all() and np.isfinite(V).all() and goal.shape == GOAL.shape and np.isfinite(goal).all()):
        raise ValueError(f"X, V and goal must be finite, goal of shape ({{DIM}},)")
    return np.hstack([(X - goal) / LENGTH, V * (TIME / LENGTH)]), single


def _tracking(E):
    out = np.empty((len(E), DIM))
    for lo in range(0, len(E), CHUNK):
        e = E[lo:lo + CHUNK]
        d2 = 0.5 * np.square((e[:, None, :] - SAMPLES[None, :, :]) * INV_WIDTHS).sum(axis=2)
        W = np.exp(-(d2 - d2.min(axis=1, keepdims=True)))
        fade = 1.0 - np.exp(-np.einsum("ij,ij->i", e, e) / (2.0 * RADIUS ** 2))
        out[lo:lo + CHUNK] = fade[:, None] * ((W @ TARGETS) / W.sum(axis=1, keepdims=True)) \\
            - OMEGA ** 2 * e[:, :DIM] - 2.0 * OMEGA * e[:, DIM:]
    return out


def _rates(E, A):
    ME = E @ METRIC
    return (np.einsum("ti,ti->t", ME, E),
            2.0 * (np.einsum("ti,ti->t", ME[:, :DIM], E[:, DIM:]) + np.einsum("ti,ti->t", ME[:, DIM:], A)))


def derivatives(X, V, tank, goal=None):
    """(accelerations, tank rates per s) at positions X, velocities V ((m, n) each, or (n,)) and tank
    levels ``tank`` ((m,) or a number, >= 0)."""
    E, single = _states(X, V, goal)
    b = np.broadcast_to(np.asarray(tank, dtype=float), (len(E),))
    with np.errstate(over="ignore", invalid="ignore"):
        A, A0 = _tracking(E), E @ WITNESS.T
        Vm, d1 = _rates(E, A)
        _, d0 = _rates(E, A0)
        allowed = -2.0 * GAMMA * Vm + RATE * np.maximum(b, 0.0)
        over = d1 > allowed
        lam = np.clip((allowed[over] - d0[over]) / (d1[over] - d0[over]), 0.0, 1.0)
        out = A.copy()
        out[over] = A0[over] + lam[:, None] * (A[over] - A0[over])
        _, d = _rates(E, out)
        bdot = -np.maximum(0.0, d + 2.0 * GAMMA * Vm) - 2.0 * GAMMA * b
        A, bdot = out * (LENGTH / TIME ** 2), bdot / TIME
    if not (np.isfinite(A).all() and np.isfinite(bdot).all()):
        raise ValueError("a state is so far from the data that the acceleration overflows float")
    return (A[0], bdot[0]) if single else (A, bdot)


def initial_tank(X, V, goal=None):
    """b(0) = BETA V(e): the tank of a motion starting at these states."""
    E, single = _states(X, V, goal)
    b = BETA * np.einsum("ti,ij,tj->t", E, METRIC, E)
    return b[0] if single else b


def acceleration(X, V, goal=None, tank=None):
    """Accelerations at positions X and velocities V ((m, n) each -> (m, n), or (n,) -> (n,)) towards
    ``goal`` (None: GOAL) with tank levels ``tank`` (None: initial_tank, a motion starting there)."""
    return derivatives(X, V, initial_tank(X, V, goal) if tank is None else tank, goal)[0]
'''


def header_prologue(model, namespace: str, state_note: str = "") -> str:
    """The lines both second-order C++ headers (tracking and mixture fields) open with: includes, the
    namespace, units, P and N (``state_note`` appended to N's comment), columns, goal and the scales."""
    n = model.dim_
    return f"""#pragma once
#include <array>
#include <cmath>

namespace {namespace} {{

constexpr const char* units = {cpp_string(str(model.units_))};
constexpr int P = {n};   // positions (and velocities)
constexpr int N = {2 * n};   // the scaled state e = ((x - g) / s, v T / s){state_note}
// the names of the position coordinates (the data's columns)
constexpr std::array<const char*, P> columns = {{{cpp_strings(model.names())}}};
constexpr std::array<double, P> goal = {{{_flat(model.goal_)}}};
constexpr double length_scale = {float(model.length_scale_)!r};   // s
constexpr double time_scale = {float(model.time_scale_)!r};   // T
"""


def tank_cpp(model, namespace: str) -> str:
    """The body of the C++17 header of a tracking ``model`` in ``namespace`` (checked by the caller)."""
    num = _numbers(model)
    N = len(num["SAMPLES"])
    return header_prologue(model, namespace) + f"""constexpr int S = {N};   // tracked samples
constexpr double omega = {num["OMEGA"]!r};   // w
constexpr double radius = {num["RADIUS"]!r};   // r: near the goal the field fades to the landing
constexpr double gamma = {num["GAMMA"]!r};   // gamma' = gamma T
constexpr double beta = {num["BETA"]!r};   // b(0) = beta V(e(0))
constexpr double rate = {num["RATE"]!r};   // rho
// samples[i * N + j] = e_i[j]; targets[i * P + j] = a_i + w^2 x_i + 2 w v_i; scaled units
constexpr std::array<double, S * N> samples = {{{_flat(num["SAMPLES"])}}};
constexpr std::array<double, S * P> targets = {{{_flat(num["TARGETS"])}}};
constexpr std::array<double, N> inv_widths = {{{_flat(num["INV_WIDTHS"])}}};
constexpr std::array<double, N * N> metric = {{{_flat(num["METRIC"])}}};   // M, row-major
constexpr std::array<double, P * N> witness = {{{_flat(num["WITNESS"])}}};   // C_0, row-major

inline bool scaled(const double* x, const double* v, const double* goal, std::array<double, N>& e) {{
  const double* g = goal != nullptr ? goal : {namespace}::goal.data();
  for (int i = 0; i < P; ++i) {{
    if (!std::isfinite(x[i]) || !std::isfinite(v[i]) || !std::isfinite(g[i])) return false;
    e[i] = (x[i] - g[i]) / length_scale;
    e[P + i] = v[i] * (time_scale / length_scale);
  }}
  return true;
}}

// V = e^T M e and (M e)
inline double energy(const std::array<double, N>& e, std::array<double, N>& me) {{
  double V = 0.0;
  for (int i = 0; i < N; ++i) {{
    double s = 0.0;
    for (int j = 0; j < N; ++j) s += e[j] * metric[j * N + i];
    me[i] = s;
    V += s * e[i];
  }}
  return V;
}}

// dV/dt' along (e_v, a)
inline double rate_of(const std::array<double, N>& e, const std::array<double, N>& me, const double* a) {{
  double x = 0.0, y = 0.0;
  for (int i = 0; i < P; ++i) {{ x += me[i] * e[P + i]; y += me[P + i] * a[i]; }}
  return 2.0 * (x + y);
}}

// the tank b(0) = beta V(e) of a motion starting at (x, v); NaN if a number is not finite
inline double initial_tank(const double* x, const double* v, const double* goal = nullptr) {{
  std::array<double, N> e{{}}, me{{}};
  if (!scaled(x, v, goal, e)) return std::nan("");
  return beta * energy(e, me);
}}

// a: the tracking field filtered by the tank *tank (>= 0), then *tank advanced by dt seconds (explicit
// Euler, kept >= 0; dt = 0 leaves it); false if a number is not finite (a and *tank then unspecified).
// A control loop: double tank = initial_tank(x0, v0); then each period acceleration(x, v, a, &tank, dt).
inline bool acceleration(const double* x, const double* v, double* a, double* tank, double dt,
                         const double* goal = nullptr) {{
  std::array<double, N> e{{}}, me{{}};
  if (!scaled(x, v, goal, e) || !std::isfinite(*tank) || !std::isfinite(dt)) return false;
  auto exponent = [&e](int i) {{     // |D (e - e_i)|^2 / 2
    double s = 0.0;
    for (int j = 0; j < N; ++j) {{ const double u = (e[j] - samples[i * N + j]) * inv_widths[j]; s += u * u; }}
    return 0.5 * s;
  }};
  double dmin = HUGE_VAL;
  for (int i = 0; i < S; ++i) {{ const double d = exponent(i); if (d < dmin) dmin = d; }}
  std::array<double, P> num{{}}, nominal{{}}, fallback{{}};
  double den = 0.0;
  for (int i = 0; i < S; ++i) {{
    const double w = std::exp(-(exponent(i) - dmin));
    den += w;
    for (int j = 0; j < P; ++j) num[j] += w * targets[i * P + j];
  }}
  double e2 = 0.0;
  for (int j = 0; j < N; ++j) e2 += e[j] * e[j];
  const double fade = 1.0 - std::exp(-e2 / (2.0 * radius * radius));
  for (int j = 0; j < P; ++j) {{
    nominal[j] = fade * (num[j] / den) - omega * omega * e[j] - 2.0 * omega * e[P + j];
    double s = 0.0;
    for (int k = 0; k < N; ++k) s += witness[j * N + k] * e[k];
    fallback[j] = s;
  }}
  const double V = energy(e, me);
  const double b = *tank > 0.0 ? *tank : 0.0;
  const double allowed = -2.0 * gamma * V + rate * b;
  const double d1 = rate_of(e, me, nominal.data());
  std::array<double, P> out = nominal;
  if (d1 > allowed) {{
    const double d0 = rate_of(e, me, fallback.data());
    double lam = (allowed - d0) / (d1 - d0);
    lam = lam < 0.0 ? 0.0 : (lam > 1.0 ? 1.0 : lam);
    for (int j = 0; j < P; ++j) out[j] = fallback[j] + lam * (nominal[j] - fallback[j]);
  }}
  const double d = rate_of(e, me, out.data());
  const double bdot = -(d + 2.0 * gamma * V > 0.0 ? d + 2.0 * gamma * V : 0.0) - 2.0 * gamma * *tank;
  bool finite = true;
  for (int j = 0; j < P; ++j) {{
    a[j] = out[j] * (length_scale / (time_scale * time_scale));
    finite = finite && std::isfinite(a[j]);
  }}
  const double next = *tank + dt * (bdot / time_scale);
  *tank = next > 0.0 ? next : 0.0;
  return finite && std::isfinite(*tank);
}}

// a at (x, v) for a motion starting there (a full tank, initial_tank): what predict(x, v) gives
inline bool acceleration(const double* x, const double* v, double* a, const double* goal = nullptr) {{
  double tank = initial_tank(x, v, goal);
  return acceleration(x, v, a, &tank, 0.0, goal);
}}

}}  // namespace {namespace}
"""


__all__ = ["tank_cpp", "tank_python"]

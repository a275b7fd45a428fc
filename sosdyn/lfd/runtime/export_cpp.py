"""The C++17 export of a fitted CDSP: a header-only evaluator (<array>, <cmath> only).

The same numbers as :meth:`sosdyn.lfd.model.cdsp.CDSP.predict` (:mod:`.export_python`'s module docstring
states the formula), every number written out in full precision.
"""
from __future__ import annotations

import math

import numpy as np

from ..fit.floor import floor_terms
from .codegen import _check, _flat, _header, _twist, _warp, check_namespace, cpp_string, cpp_strings
from .states import CPP_SPEED_LIMIT, check_max_speed


def _floor_cpp(rate: float, boost: float, radius: float) -> str:
    """The speed floor's lines (:mod:`~sosdyn.lfd.fit.floor`): xdot scaled by sigma, the rate faded out
    from radius / 2 to radius when the floor has a settle zone."""
    fade = "" if math.isinf(radius) else f"""  // the settle zone: the rate faded from 1 at radius / 2 to 0 at radius (smoothstep)
  const double s = std::fmin(1.0, std::fmax(0.0, 2.0 * (1.0 - dmax * std::sqrt(d2) / {radius!r})));
  want *= s * s * (3.0 - 2.0 * s);
"""
    return f"""  // the speed floor: xdot scaled by min(boost, max(1, rate |x - g| / |xdot|))
  double dmax = 0.0, vmax = 0.0, d2 = 0.0, v2 = 0.0;     // norms scaled by the largest entry: no overflow
  for (int i = 0; i < N; ++i) {{ dmax = std::fmax(dmax, std::fabs(x[i] - g[i])); vmax = std::fmax(vmax, std::fabs(xdot[i])); }}
  for (int i = 0; i < N; ++i) {{
    if (dmax > 0.0) d2 += ((x[i] - g[i]) / dmax) * ((x[i] - g[i]) / dmax);
    if (vmax > 0.0) v2 += (xdot[i] / vmax) * (xdot[i] / vmax);
  }}
  double want = {rate!r} * dmax * std::sqrt(d2);
{fade}  const double speed = vmax * std::sqrt(v2), boost = {boost!r};
  const double sigma = speed > 0.0 ? std::fmin(boost, std::fmax(1.0, want / speed)) : (want > 0.0 ? boost : 1.0);
  for (int i = 0; i < N; ++i) xdot[i] *= sigma;
"""


def to_cpp(model, namespace: str = "cdsp_model", max_speed: float | None = None) -> str:
    """Source of a header-only C++17 evaluator (<array>, <cmath> only) in ``namespace``:
    ``bool predict(const double* x, double* xdot, const double* goal = nullptr)`` for one state
    of N doubles (``goal``: N doubles, nullptr = the model's); false when the velocity is not
    finite (x or goal not finite, or so far from the data that the field overflows). With
    ``max_speed`` xdot is scaled to |xdot| <= max_speed.

    The Cholesky factors of the mixture are precomputed here (L_k^-1 and the log normalisers)."""
    _check(model)
    max_speed = check_max_speed(max_speed)
    namespace = check_namespace(namespace, "cdsp_model")
    K, n, m = model.C_.shape
    warp, twist = _warp(model), _twist(model)
    twist_defs = "" if twist is None else f"""
// The twist after the bumps, z-units: u <- R(alpha(|u|)) u, a rotation in the plane (p, q) by
// alpha(r) = sum_j a_j (1 - exp(-r^2 / tau_j^2)); J <- J_T J, J_T = R (I + beta (S u) u^T),
// beta = alpha'(r) / r, S u = (p.u) q - (q.u) p; twist_inv_w2[j] = 1 / tau_j^2.
constexpr int TW = {len(twist[1])};
constexpr std::array<double, N> twist_p = {{{_flat(twist[0][0])}}};
constexpr std::array<double, N> twist_q = {{{_flat(twist[0][1])}}};
constexpr std::array<double, TW> twist_amp = {{{_flat(twist[1])}}};
constexpr std::array<double, TW> twist_inv_w2 = {{{_flat(1.0 / np.asarray(twist[2], dtype=float) ** 2)}}};

// x <- x + ((c - 1) p.x - s q.x) p + ((c - 1) q.x + s p.x) q: R(alpha) x, c = cos alpha, s = sin alpha.
inline void rotate(double* x, int stride, double c, double s) {{
  double d0 = 0.0, d1 = 0.0;
  for (int i = 0; i < N; ++i) {{ d0 += twist_p[i] * x[i * stride]; d1 += twist_q[i] * x[i * stride]; }}
  const double a0 = (c - 1.0) * d0 - s * d1, a1 = (c - 1.0) * d1 + s * d0;
  for (int i = 0; i < N; ++i) x[i * stride] += a0 * twist_p[i] + a1 * twist_q[i];
}}

inline void twist(double* u, double* J) {{
  double r2 = 0.0;
  for (int i = 0; i < N; ++i) r2 += u[i] * u[i];
  double alpha = 0.0, beta = 0.0;
  for (int j = 0; j < TW; ++j) {{
    const double e = std::exp(-twist_inv_w2[j] * r2);
    alpha += twist_amp[j] * (1.0 - e);
    beta += 2.0 * twist_amp[j] * twist_inv_w2[j] * e;
  }}
  double c0 = 0.0, c1 = 0.0;
  for (int i = 0; i < N; ++i) {{ c0 += twist_p[i] * u[i]; c1 += twist_q[i] * u[i]; }}
  std::array<double, N> uJ{{}};     // u^T J
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) uJ[b] += u[a] * J[a * N + b];
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) J[a * N + b] += beta * (c0 * twist_q[a] - c1 * twist_p[a]) * uJ[b];
  const double c = std::cos(alpha), s = std::sin(alpha);
  for (int b = 0; b < N; ++b) rotate(J + b, N, c, s);
  rotate(u, 1, c, s);
}}
"""
    twist_call = "" if twist is None else "\n  twist(u, J);"
    warp_defs = "" if warp is None else f"""
// The warp u = phi(z), z-units: phi = psi_W o ... o psi_1, psi_j(z) = z + (rho_j(z) - rho_j(0)) v_j,
// rho_j(z) = exp(-|z - c_j|^2 / sigma_j^2); warp_centers/vectors[j * N + i], warp_rho0[j] = rho_j(0).
constexpr int W = {len(warp[2])};
constexpr std::array<double, W * N> warp_centers = {{{_flat(warp[0])}}};
constexpr std::array<double, W * N> warp_vectors = {{{_flat(warp[1])}}};
constexpr std::array<double, W> warp_sigmas = {{{_flat(warp[2])}}};
constexpr std::array<double, W> warp_rho0 = {{{_flat(np.exp(-np.sum(warp[0] ** 2, axis=1) / warp[2] ** 2))}}};

// u <- phi(u) and J <- J_phi(u) (row-major N x N), by the chain rule J <- (I + v_j grad rho_j^T) J.
inline void warp(double* u, double* J) {{
  for (int i = 0; i < N * N; ++i) J[i] = (i % (N + 1) == 0) ? 1.0 : 0.0;
  for (int j = 0; j < W; ++j) {{
    std::array<double, N> d{{}};
    double dd = 0.0;
    for (int i = 0; i < N; ++i) {{
      d[i] = u[i] - warp_centers[j * N + i];
      dd += d[i] * d[i];
    }}
    const double s2 = warp_sigmas[j] * warp_sigmas[j];
    const double rho = std::exp(-dd / s2);
    std::array<double, N> row{{}};   // grad rho^T J
    for (int b = 0; b < N; ++b)
      for (int a = 0; a < N; ++a) row[b] += (-2.0 / s2) * rho * d[a] * J[a * N + b];
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b) J[a * N + b] += warp_vectors[j * N + a] * row[b];
    for (int i = 0; i < N; ++i) u[i] += (rho - warp_rho0[j]) * warp_vectors[j * N + i];
  }}{twist_call}
}}

// Solves A y = b in place (y in b; A row-major N x N, overwritten) by Gaussian elimination with
// partial pivoting; false if a pivot is zero or not finite.
inline bool solve(double* A, double* b) {{
  for (int c = 0; c < N; ++c) {{
    int p = c;
    for (int r = c + 1; r < N; ++r) p = std::fabs(A[r * N + c]) > std::fabs(A[p * N + c]) ? r : p;
    if (!(std::fabs(A[p * N + c]) > 0.0) || !std::isfinite(A[p * N + c])) return false;
    if (p != c) {{
      for (int k = 0; k < N; ++k) {{ const double t = A[c * N + k]; A[c * N + k] = A[p * N + k]; A[p * N + k] = t; }}
      const double t = b[c]; b[c] = b[p]; b[p] = t;
    }}
    for (int r = c + 1; r < N; ++r) {{
      const double f = A[r * N + c] / A[c * N + c];
      for (int k = c; k < N; ++k) A[r * N + k] -= f * A[c * N + k];
      b[r] -= f * b[c];
    }}
  }}
  for (int r = N - 1; r >= 0; --r) {{
    double v = b[r];
    for (int k = r + 1; k < N; ++k) v -= A[r * N + k] * b[k];
    b[r] = v / A[r * N + r];
  }}
  return true;
}}
"""
    to_u = "" if warp is None else """  std::array<double, N * N> J{};
  warp(z.data(), J.data());         // z <- u = phi(z), J = J_phi(z)
"""
    from_u = "" if warp is None else """  if (finite && !solve(J.data(), xdot)) return false;   // xdot <- J^-1 xdot
  for (int i = 0; i < N; ++i) finite = finite && std::isfinite(xdot[i]);
"""
    limit = "" if max_speed is None else "  if (finite) limit_speed(xdot, N, max_speed);\n"
    floor = "" if model.floor_ is None else _floor_cpp(*floor_terms(model.floor_))
    speed_def = "" if max_speed is None else (
        f"// the largest |xdot| (units/s): the speed limit below\n"
        f"constexpr double max_speed = {max_speed!r};\n")
    return _header(model, "//", max_speed) + f"""#pragma once
#include <array>
#include <cmath>

namespace {namespace} {{

constexpr const char* units = {cpp_string(str(model.units_))};
constexpr int N = {n};   // state dimension
// the names of the state's coordinates (the data's position columns)
constexpr std::array<const char*, N> columns = {{{cpp_strings(model.names())}}};
constexpr int K = {K};   // mixture components
constexpr int M = {m};   // monomials of each field
constexpr std::array<double, N> goal = {{{_flat(model.goal_)}}};
constexpr double scale = {float(model.scale_)!r};
{speed_def}constexpr std::array<int, M * N> exponents = {{{", ".join(str(int(e)) for e in model.field_exps_.ravel())}}};
// coefficients[(k * N + i) * M + j] = C[k, i, j]
constexpr std::array<double, K * N * M> coefficients = {{{_flat(model.C_)}}};
{cpp_mixture(model.mixture_)}{twist_defs}{warp_defs}
{CPP_SPEED_LIMIT}
// xdot = scale * sum_k h_k(z) f_k(z), z = (x - g) / scale (with a warp: scale * J^-1 sum_k h_k(u) f_k(u),
// u = phi(z)), g = goal (N doubles) or, for nullptr, the model's; false if xdot is not finite.
inline bool predict(const double* x, double* xdot, const double* goal = nullptr) {{
  const double* g = goal != nullptr ? goal : {namespace}::goal.data();
  std::array<double, N> z{{}};
  for (int i = 0; i < N; ++i) {{
    if (!std::isfinite(x[i]) || !std::isfinite(g[i])) return false;
    z[i] = (x[i] - g[i]) / scale;
  }}
{to_u}  std::array<double, M> mono{{}};
  for (int j = 0; j < M; ++j) {{
    double v = 1.0;
    for (int i = 0; i < N; ++i)
      if (exponents[j * N + i] != 0) v *= std::pow(z[i], static_cast<double>(exponents[j * N + i]));
    mono[j] = v;
  }}
  std::array<double, K> h{{}};
  responsibilities(z.data(), h.data());
  bool finite = true;
  for (int i = 0; i < N; ++i) {{
    double v = 0.0;
    for (int k = 0; k < K; ++k) {{
      double f = 0.0;
      for (int j = 0; j < M; ++j) f += coefficients[(k * N + i) * M + j] * mono[j];
      v += h[k] * f;
    }}
    xdot[i] = v * scale;
    finite = finite && std::isfinite(xdot[i]);
  }}
{from_u}{floor}{limit}  return finite;
}}

}}  // namespace {namespace}
"""


def cpp_mixture(mixture) -> str:
    """The C++ of the gating h_k(z) (:mod:`~sosdyn.lfd.fit.gmm`) for a header that defines N (the
    mixture's dimension) and K: its numbers (L_k^-1 and the log normalisers precomputed here) and
    ``responsibilities(z, h)``; shared by the first- and second-order exports."""
    inv, lognorm = mixture.factors()
    return f"""constexpr std::array<double, K * N> means = {{{_flat(mixture.means)}}};
// inv_chol[(k * N + a) * N + b] = (L_k^-1)[a, b], S_k = L_k L_k^T
constexpr std::array<double, K * N * N> inv_chol = {{{_flat(inv)}}};
// log pi_k - log det L_k - N/2 log(2 pi)
constexpr std::array<double, K> log_norm = {{{_flat(lognorm)}}};
// the gating's bound c (0: not tempered): where min_k q_k > c, tau = min_k q_k / c and the forms are
// divided by tau; its fade F (0: none): where tau > F, l_k - log pi_k is divided by tau / F (weights -> pi)
constexpr double bound = {0.0 if mixture.bound is None else float(mixture.bound)!r};
constexpr double fade = {0.0 if mixture.bound is None or mixture.fade is None else float(mixture.fade)!r};
// log pi_k
constexpr std::array<double, K> log_weights = {{{_flat(np.log(mixture.weights))}}};

// Squared norm of L_k^-1 (z / c - mu_k / c).
inline double whitened_sq(int k, const double* z, double c) {{
  double q = 0.0;
  for (int a = 0; a < N; ++a) {{
    double s = 0.0;
    for (int b = 0; b < N; ++b)
      s += inv_chol[(k * N + a) * N + b] * (z[b] / c - means[k * N + b] / c);
    q += s * s;
  }}
  return q;
}}

// h = softmax(l) in place (l finite).
inline void softmax(double* l) {{
  double top = l[0];
  for (int k = 1; k < K; ++k) top = l[k] > top ? l[k] : top;
  double sum = 0.0;
  for (int k = 0; k < K; ++k) sum += std::exp(l[k] - top);
  const double lse = top + std::log(sum);
  for (int k = 0; k < K; ++k) l[k] = std::exp(l[k] - lse);
}}

// h_k(z): softmax of l_k = log pi_k + log N(z; mu_k, S_k), the quadratic forms q_k divided by
// tau = max(1, min_k q_k / bound) (tempered: bound > 0; bound = 0: not tempered), and where
// tau > fade > 0, l_k <- log pi_k + (l_k - log pi_k) fade / tau; where a form is not finite, one-hot on
// the nearest component (Mahalanobis), tempered the softmax of log_norm_k - bound/2 (d_k / d_min)^2,
// with a fade pi.
inline void responsibilities(const double* z, double* h) {{
  std::array<double, K> q{{}};
  bool finite = true;
  double qmin = 0.0;
  for (int k = 0; k < K; ++k) {{
    q[k] = whitened_sq(k, z, 1.0);
    finite = finite && std::isfinite(q[k]);
    qmin = (k == 0 || q[k] < qmin) ? q[k] : qmin;
  }}
  if (finite) {{
    const double tau = (bound > 0.0 && qmin > bound) ? qmin / bound : 1.0;
    for (int k = 0; k < K; ++k) {{
      h[k] = log_norm[k] - 0.5 * (tau == 1.0 ? q[k] : q[k] / tau);
      if (fade > 0.0 && tau > fade) h[k] = log_weights[k] + (h[k] - log_weights[k]) / (tau / fade);
    }}
    softmax(h);
    return;
  }}
  if (fade > 0.0) {{
    for (int k = 0; k < K; ++k) h[k] = std::exp(log_weights[k]);
    return;
  }}
  double c = 1.0;
  for (int i = 0; i < N; ++i) c = std::fabs(z[i]) > c ? std::fabs(z[i]) : c;
  int best = 0;
  double best_d = 0.0;
  for (int k = 0; k < K; ++k) {{
    const double d = std::log(c) + 0.5 * std::log(whitened_sq(k, z, c));
    if (k == 0 || d < best_d) {{ best = k; best_d = d; }}
    h[k] = d;                        // log d_k
  }}
  if (bound > 0.0) {{
    for (int k = 0; k < K; ++k) h[k] = log_norm[k] - 0.5 * bound * std::exp(2.0 * (h[k] - best_d));
    softmax(h);
    return;
  }}
  for (int k = 0; k < K; ++k) h[k] = 0.0;
  h[best] = 1.0;
}}

"""

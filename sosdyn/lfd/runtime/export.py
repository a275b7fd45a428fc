"""Code generation: a fitted CDSP as a standalone evaluator (Python + numpy, or header-only C++17).

The generated code computes what :meth:`sosdyn.lfd.model.cdsp.CDSP.predict` computes, with every
number of the model written out in full precision (``repr`` of a float round-trips exactly):

    z = (x - x*) / s,    xdot = s * sum_k h_k(z) f_k(z),    f_k,i(z) = sum_j C[k, i, j] z^e_j

    l_k(z) = log pi_k - sum_i log L_k,ii - n/2 log 2 pi - 1/2 |L_k^-1 (z - mu_k)|^2   (S_k = L_k L_k^T)
    h_k(z) = exp(l_k - logsumexp_i l_i)

and, where no l_k is finite (the quadratic forms overflow, |z| ~ 1e154 and up), h one-hot on
the component of least Mahalanobis distance, evaluated with the rescaling of
:meth:`sosdyn.lfd.fit.gmm.PositionMixture.log_mahalanobis`. A warped model (``warp_``, :mod:`.warp`)
evaluates the same sum at u = phi(z) and returns s J_phi(z)^-1 (...): the bump maps and their
chain-rule Jacobian, then one n x n solve (numpy's, or Gaussian elimination with partial pivoting
in the C++). The generated code never imports
sosdyn: it is meant to run on a robot that has numpy (Python) or a C++17 compiler only.
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import NotFittedError

TARGETS = ("python", "cpp")


def _literal(a) -> str:
    """``a`` as a nested Python list literal of exactly round-tripping numbers."""
    return repr(np.asarray(a).tolist())


def _flat(a) -> str:
    """``a`` flattened (C order) as a C++ initialiser list of exactly round-tripping doubles."""
    return ", ".join(repr(float(v)) for v in np.asarray(a, dtype=float).ravel())


def _check(model) -> None:
    if not hasattr(model, "C_"):
        raise NotFittedError("only a fitted CDSP can be exported. Try: model.fit(demos) or "
                             "sosdyn.load_model(path) first.")


def _warp(model):
    """The model's warp (centers, vectors, sigmas) in z-units, or None."""
    w = getattr(model, "warp_", None)
    return None if w is None else (w["centers"], w["vectors"], w["sigmas"])


def _header(model, comment: str) -> str:
    K, n, m = model.C_.shape
    warp = _warp(model)
    formula = ("xdot = s * sum_k h_k(z) f_k(z), z = (x - goal) / s" if warp is None else
               f"xdot = s * J_phi(z)^-1 sum_k h_k(u) f_k(u), u = phi(z), z = (x - goal) / s, {len(warp[2])} bumps")
    return (f"{comment} CDSP motion model: n = {n} state dimensions, K = {K} components, {m} monomials of "
            f"degree 1..{int(model.field_exps_.sum(axis=1).max())}, units {model.units_}.\n"
            f"{comment} Generated code (do not edit): {formula}.\n"
            f"{comment} The contraction certificate was checked when the model was fitted / loaded;\n"
            f"{comment} this file only evaluates the field.\n")


def to_python(model) -> str:
    """Source of a standalone Python module (numpy only) with ``predict(X) -> ndarray``:
    X of shape (m, n) gives (m, n), X of shape (n,) gives (n,)."""
    _check(model)
    mix, warp = model.mixture_, _warp(model)
    warp_defs = "" if warp is None else f'''
# the warp u = phi(z), z-units: phi = psi_m o ... o psi_1, psi_j(z) = z + (rho_j(z) - rho_j(0)) v_j,
# rho_j(z) = exp(-|z - c_j|^2 / sigma_j^2)
WARP_CENTERS = np.array({_literal(warp[0])}).reshape(-1, {model.dim_})
WARP_VECTORS = np.array({_literal(warp[1])}).reshape(-1, {model.dim_})
WARP_SIGMAS = np.array({_literal(warp[2])}, dtype=float)


def warp(Z):
    """(phi(Z), J_phi(Z)) at the rows of Z: (N, n) and (N, n, n), by the chain rule."""
    U = np.array(Z, dtype=float)
    J = np.broadcast_to(np.eye(U.shape[1]), (U.shape[0],) + (U.shape[1],) * 2).copy()
    for c, v, s in zip(WARP_CENTERS, WARP_VECTORS, WARP_SIGMAS):
        rho = np.exp(-np.sum((U - c) ** 2, axis=-1) / s ** 2)
        grad = (-2.0 / s ** 2) * rho[:, None] * (U - c)
        J += v[None, :, None] * np.einsum("ki,kij->kj", grad, J)[:, None, :]
        U += (rho - np.exp(-np.sum((0.0 - c) ** 2) / s ** 2))[:, None] * v
    return U, J
'''
    core = ("    with np.errstate(over=\"ignore\", invalid=\"ignore\"):\n"
            "        F = np.einsum(\"kij,nj->nki\", COEFFICIENTS, monomials(Z))\n"
            "        V = np.einsum(\"tk,tki->ti\", responsibilities(Z), F) * SCALE\n") if warp is None else (
            "    U, J = warp(Z)\n"
            "    with np.errstate(over=\"ignore\", invalid=\"ignore\"):\n"
            "        F = np.einsum(\"kij,nj->nki\", COEFFICIENTS, monomials(U))\n"
            "        W = np.einsum(\"tk,tki->ti\", responsibilities(U), F)\n"
            "        V = np.linalg.solve(J, W[:, :, None])[:, :, 0] * SCALE\n")
    return _header(model, "#") + f'''"""Standalone evaluator of a CDSP motion model: predict(X) -> velocities."""
import numpy as np

GOAL = np.array({_literal(model.goal_)})
SCALE = {float(model.scale_)!r}
# the mixture of h_k(z), in z coordinates: weights pi_k, means mu_k, covariances S_k
WEIGHTS = np.array({_literal(mix.weights)})
MEANS = np.array({_literal(mix.means)})
COVARIANCES = np.array({_literal(mix.covariances)})
EXPONENTS = np.array({_literal(model.field_exps_)}, dtype=np.int64)
COEFFICIENTS = np.array({_literal(model.C_)})     # (K, n, m): f_k,i(z) = sum_j C[k, i, j] z^e_j

DIM = GOAL.size
_CHOL = np.linalg.cholesky(COVARIANCES)
_INV = np.linalg.inv(_CHOL)
_LOGNORM = (np.log(WEIGHTS) - np.log(np.diagonal(_CHOL, axis1=1, axis2=2)).sum(axis=1)
            - 0.5 * DIM * np.log(2 * np.pi))
{warp_defs}

def monomials(Z):
    """(N, m) values z^e_j at the rows of Z."""
    out = np.ones((Z.shape[0], EXPONENTS.shape[0]))
    for i in range(EXPONENTS.shape[1]):
        if EXPONENTS[:, i].any():
            out *= Z[:, i:i + 1] ** EXPONENTS[None, :, i]
    return out


def responsibilities(Z):
    """h_k(z), (N, K): softmax of log pi_k + log N(z; mu_k, S_k); one-hot on the nearest
    component (Mahalanobis) where every term under- or overflows."""
    with np.errstate(over="ignore", invalid="ignore"):
        d = np.einsum("kij,mkj->mki", _INV, Z[:, None, :] - MEANS[None])
        lj = _LOGNORM[None, :] - 0.5 * np.einsum("mki,mki->mk", d, d)
    far = ~np.isfinite(lj).any(axis=1) | np.isnan(lj).any(axis=1)
    lj[far] = 0.0
    top = lj.max(axis=1, keepdims=True)
    lse = top + np.log(np.exp(lj - top).sum(axis=1, keepdims=True))
    h = np.exp(lj - lse)
    if far.any():
        Zf = Z[far]
        c = np.maximum(np.abs(Zf).max(axis=1), 1.0)[:, None, None]
        d = np.einsum("kij,mkj->mki", _INV, Zf[:, None, :] / c - MEANS[None] / c)
        with np.errstate(divide="ignore"):
            logdist = np.log(c[:, :, 0]) + 0.5 * np.log(np.einsum("mki,mki->mk", d, d))
        h[far] = np.eye(WEIGHTS.size)[np.argmin(logdist, axis=1)]
    return h


def predict(X):
    """Velocities at the states X: shape (m, n) -> (m, n), or (n,) -> (n,)."""
    X = np.asarray(X, dtype=float)
    single = X.ndim == 1
    X = X[None, :] if single else X
    if X.ndim != 2 or X.shape[1] != DIM:
        raise ValueError(f"X must have shape (m, {{DIM}}) or ({{DIM}},), got {{np.shape(X)}}")
    if not np.isfinite(X).all():
        raise ValueError("X contains NaN or inf")
    Z = (X - GOAL) / SCALE
{core}    bad = np.flatnonzero(~np.isfinite(V).all(axis=1))
    if bad.size:
        raise ValueError(f"X row {{bad[0]}} is so far from the data (scale {{SCALE:.3g}}) that the field "
                         "overflows float. Try: states within a few orders of magnitude of the data.")
    return V[0] if single else V
'''


def to_cpp(model, namespace: str = "cdsp_model") -> str:
    """Source of a header-only C++17 evaluator (<array>, <cmath> only) in ``namespace``:
    ``bool predict(const double* x, double* xdot)`` for one state of N doubles; false when
    the velocity is not finite (x not finite, or so far from the data that the field overflows).

    The Cholesky factors of the mixture are precomputed here (L_k^-1 and the log normalisers)."""
    _check(model)
    if not namespace.isidentifier():
        raise ValueError(f"namespace must be a C++ identifier, got {namespace!r}")
    K, n, m = model.C_.shape
    inv, lognorm = model.mixture_.factors()
    warp = _warp(model)
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
  }}
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
    return _header(model, "//") + f"""#pragma once
#include <array>
#include <cmath>

namespace {namespace} {{

constexpr int N = {n};   // state dimension
constexpr int K = {K};   // mixture components
constexpr int M = {m};   // monomials of each field
constexpr std::array<double, N> goal = {{{_flat(model.goal_)}}};
constexpr double scale = {float(model.scale_)!r};
constexpr std::array<int, M * N> exponents = {{{", ".join(str(int(e)) for e in model.field_exps_.ravel())}}};
// coefficients[(k * N + i) * M + j] = C[k, i, j]
constexpr std::array<double, K * N * M> coefficients = {{{_flat(model.C_)}}};
constexpr std::array<double, K * N> means = {{{_flat(model.mixture_.means)}}};
// inv_chol[(k * N + a) * N + b] = (L_k^-1)[a, b], S_k = L_k L_k^T
constexpr std::array<double, K * N * N> inv_chol = {{{_flat(inv)}}};
// log pi_k - log det L_k - N/2 log(2 pi)
constexpr std::array<double, K> log_norm = {{{_flat(lognorm)}}};
{warp_defs}
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

// h_k(z): softmax of log pi_k + log N(z; mu_k, S_k), one-hot on the nearest component
// (Mahalanobis) where no term is finite.
inline void responsibilities(const double* z, double* h) {{
  std::array<double, K> l{{}};
  bool any_finite = false, any_nan = false;
  for (int k = 0; k < K; ++k) {{
    l[k] = log_norm[k] - 0.5 * whitened_sq(k, z, 1.0);
    any_finite = any_finite || std::isfinite(l[k]);
    any_nan = any_nan || std::isnan(l[k]);
  }}
  if (any_finite && !any_nan) {{
    double top = l[0];
    for (int k = 1; k < K; ++k) top = l[k] > top ? l[k] : top;
    double sum = 0.0;
    for (int k = 0; k < K; ++k) sum += std::exp(l[k] - top);
    const double lse = top + std::log(sum);
    for (int k = 0; k < K; ++k) h[k] = std::exp(l[k] - lse);
    return;
  }}
  double c = 1.0;
  for (int i = 0; i < N; ++i) c = std::fabs(z[i]) > c ? std::fabs(z[i]) : c;
  int best = 0;
  double best_d = 0.0;
  for (int k = 0; k < K; ++k) {{
    const double d = std::log(c) + 0.5 * std::log(whitened_sq(k, z, c));
    if (k == 0 || d < best_d) {{ best = k; best_d = d; }}
    h[k] = 0.0;
  }}
  h[best] = 1.0;
}}

// xdot = scale * sum_k h_k(z) f_k(z), z = (x - goal) / scale (with a warp: scale * J^-1 sum_k h_k(u) f_k(u),
// u = phi(z)); false if xdot is not finite.
inline bool predict(const double* x, double* xdot) {{
  std::array<double, N> z{{}};
  for (int i = 0; i < N; ++i) {{
    if (!std::isfinite(x[i])) return false;
    z[i] = (x[i] - goal[i]) / scale;
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
{from_u}  return finite;
}}

}}  // namespace {namespace}
"""


def export(model, target: str) -> str:
    """The source of ``model`` for ``target`` ("python" or "cpp")."""
    if target not in TARGETS:
        raise ValueError(f"unknown export target {target!r}. Try: one of {', '.join(TARGETS)}.")
    return to_python(model) if target == "python" else to_cpp(model)

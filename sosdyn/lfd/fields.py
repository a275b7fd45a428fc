"""Polynomial sub-systems f_k(z) and the polynomial metric M(z), as numbers and as SOS data.

Coordinates are goal-shifted and scaled, z = (x - x*) / s, so the equilibrium condition
(5) A_k x* + b_k = 0 becomes f_k(0) = 0: every f_k has monomials of degree 1..F only.

* fields:  f_k,i(z) = sum_j C[k, i, j] z^e_j       (e_j: ``field_exps``, |e_j| in 1..F)
* metric:  M_ab(z) = sum_j W[a, b, j] z^g_j          (g_j: ``metric_exps``, |g_j| in 0..D)

The contraction operator of eq. (4)/(13), generalised to polynomial f_k (the virtual system
ydot = sum_k h_k(x) f_k(y) of Theorem 1):

    G_k(z) = J_k(z)^T M(z) + M(z) J_k(z) + dM(z)[f_k(z)] + gamma M(z)  <= 0 for all z.
"""
from __future__ import annotations

import numpy as np

from ..poly import PolyMatrix, Polynomial, monomials_up_to


def monomial_values(Z: np.ndarray, exps: np.ndarray) -> np.ndarray:
    """(N, m) values z^e_j at the rows of Z."""
    out = np.ones((Z.shape[0], exps.shape[0]))
    for i in range(exps.shape[1]):
        if exps[:, i].any():
            out *= Z[:, i:i + 1] ** exps[None, :, i]
    return out


def monomial_gradients(Z: np.ndarray, exps: np.ndarray) -> np.ndarray:
    """(N, n, m): d z^e_j / d z_i."""
    N, n = Z.shape
    out = np.zeros((N, n, exps.shape[0]))
    for i in range(n):
        e = exps[:, i]
        lowered = exps.copy()
        lowered[:, i] = np.maximum(e - 1, 0)
        out[:, i, :] = monomial_values(Z, lowered) * e[None, :]
    return out


def field_exponents(n: int, degree: int) -> np.ndarray:
    return monomials_up_to(n, degree, 1)


def metric_exponents(n: int, degree: int) -> np.ndarray:
    return monomials_up_to(n, degree, 0)


def symmetric_pairs(n: int):
    return [(a, b) for a in range(n) for b in range(a, n)]


# ---------------------------------------------------------------------- numeric evaluation
def eval_fields(C, exps, Z):
    """f_k(z) for every component: (N, K, n)."""
    return np.einsum("kij,nj->nki", C, monomial_values(Z, exps))


def eval_jacobians(C, exps, Z):
    """J_k(z) = df_k/dz: (N, K, n, n)."""
    return np.einsum("kij,nlj->nkil", C, monomial_gradients(Z, exps))


def eval_metric(W, exps, Z):
    """M(z): (N, n, n)."""
    return np.einsum("abj,nj->nab", W, monomial_values(Z, exps))


def eval_metric_gradient(W, exps, Z):
    """dM/dz_l: (N, n_l, n, n)."""
    return np.einsum("abj,nlj->nlab", W, monomial_gradients(Z, exps))


def contraction_matrices(C, fexps, W, mexps, Z, gamma):
    """G_k(z) at the rows of Z: (N, K, n, n) (see module docstring)."""
    J = eval_jacobians(C, fexps, Z)
    F = eval_fields(C, fexps, Z)
    M = eval_metric(W, mexps, Z)[:, None]
    dM = eval_metric_gradient(W, mexps, Z)
    Mdot = np.einsum("nlab,nkl->nkab", dM, F)
    JtM = np.einsum("nkia,nkib->nkab", J, M.repeat(J.shape[1], axis=1))
    return JtM + np.swapaxes(JtM, -1, -2) + Mdot + gamma * M


def generalized_max_eig(G, M):
    """max_k lambda_max(M^-1/2 G_k M^-1/2) per sample; G (N, K, n, n), M (N, n, n)."""
    L = np.linalg.cholesky(M)
    Linv = np.linalg.inv(L)[:, None]
    S = Linv @ G @ np.swapaxes(Linv, -1, -2)
    return np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))[..., -1].max(axis=1)


# ---------------------------------------------------------------------- SOS data
def decision_fields(ids, exps, vars):
    """f_k,i(z) with coefficients the decision ids ``ids`` (K, n, m): list of lists of Polynomials."""
    K, n, m = ids.shape
    coef = np.hstack([np.zeros((m, 1)), np.eye(m)])
    return [[Polynomial(vars, exps, coef, ids[k, i]) for i in range(n)] for k in range(K)]


def numeric_fields(C, exps, vars):
    return [[Polynomial(vars, exps, C[k, i]) for i in range(C.shape[1])] for k in range(C.shape[0])]


def decision_metric(ids_by_pair, exps, vars, n):
    """Symmetric PolyMatrix whose entry (a, b) has coefficients ``ids_by_pair[(a, b)]``."""
    m = exps.shape[0]
    coef = np.hstack([np.zeros((m, 1)), np.eye(m)])
    entries = np.empty((n, n), dtype=object)
    for a, b in symmetric_pairs(n):
        entries[a, b] = entries[b, a] = Polynomial(vars, exps, coef, ids_by_pair[(a, b)])
    return PolyMatrix(entries)


def numeric_metric(W, exps, vars):
    n = W.shape[0]
    return PolyMatrix([[Polynomial(vars, exps, W[a, b]) for b in range(n)] for a in range(n)])


def contraction_polymatrix(f, M, vars, gamma):
    """G(z) = J^T M + M J + dM[f] + gamma M as a PolyMatrix (f: list of n Polynomials)."""
    from ..poly import jacobian
    J = jacobian(f, vars)
    JtM = J.T @ M
    return JtM + JtM.T + M.directional_derivative(f, vars) + gamma * M


def unit_metrics(mexps, n, vars):
    """[((a, b, j), E)]: E has z^g_j at (a, b) and (b, a), so M = sum W[a, b, j] E."""
    out = []
    for a, b in symmetric_pairs(n):
        for j in range(mexps.shape[0]):
            entries = np.zeros((n, n), dtype=object)
            mono = Polynomial(vars, mexps[j:j + 1], [1.0])
            for idx in np.ndindex(n, n):
                entries[idx] = Polynomial.constant(0.0, vars)
            entries[a, b] = entries[b, a] = mono
            out.append(((a, b, j), PolyMatrix(entries)))
    return out


def unit_fields(fexps, n, vars):
    """[((i, j), f)]: the field with z^e_j in component i and zeros elsewhere."""
    zero = Polynomial.constant(0.0, vars)
    return [((i, j), [Polynomial(vars, fexps[j:j + 1], [1.0]) if r == i else zero for r in range(n)])
            for i in range(n) for j in range(fexps.shape[0])]

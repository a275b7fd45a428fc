"""The contraction condition of CDSP: fields f_k(z), metric M(z) and G_k(z), as numbers and as SOS data.

Coordinates are goal-shifted and scaled, z = (x - x*) / s, so the equilibrium condition
(5) A_k x* + b_k = 0 becomes f_k(0) = 0: every f_k has monomials of degree 1..F only.

* fields:  f_k,i(z) = sum_j C[k, i, j] z^e_j       (e_j: ``field_exps``, |e_j| in 1..F)
* metric:  M_ab(z) = sum_j W[a, b, j] z^g_j          (g_j: ``metric_exps``, |g_j| in 0..D)

The contraction operator of eq. (4)/(13), generalised to polynomial f_k (the virtual system
ydot = sum_k h_k(x) f_k(y) of Theorem 1):

    G_k(z) = J_k(z)^T M(z) + M(z) J_k(z) + dM(z)[f_k(z)] + gamma M(z)  <= 0 for all z.

The certificate is: M - eps I and -G_1 .. -G_K are SOS matrices (:func:`certificate_matrices`,
the one builder used to certify and to check). Its sampled counterpart is the largest
generalised eigenvalue of (G_k(z), M(z)) at states of twice the data box
(:func:`sample_states`, :func:`sampled_eigenvalues`).
"""
from __future__ import annotations

import numpy as np

from sosdyn.poly import PolyMatrix, Polynomial, monomial_gradients, monomial_values, monomials_up_to, variable_names
from sosdyn.poly.termarrays import (Terms, concat_terms, matrix_terms, terms_directional_derivative, terms_jacobian,
                               terms_matmul, terms_scale, terms_transpose)

SAMPLE_BOX = 2.0            # sampled states lie in |z|_inf <= 2: twice the data box


# ---------------------------------------------------------------------- monomials and degrees
def field_exponents(n: int, degree: int) -> np.ndarray:
    return monomials_up_to(n, degree, 1)


def metric_exponents(n: int, degree: int) -> np.ndarray:
    return monomials_up_to(n, degree, 0)


def symmetric_pairs(n: int):
    return [(a, b) for a in range(n) for b in range(a, n)]


def state_variables(n: int) -> tuple:
    """The names of z: ("z1", ..., "zn")."""
    return tuple(f"z{i + 1}" for i in range(n))


def degree(exps) -> int:
    """Largest total degree of the exponent rows."""
    return int(exps.sum(axis=1).max())


def constant_index(exps) -> int:
    """Row of the constant monomial z^0 in ``exps``."""
    return int(np.flatnonzero(exps.sum(axis=1) == 0)[0])


def contraction_degree(metric_degree: int, field_degree: int) -> int:
    """Degree of G_k(z): deg M + deg f_k - 1 (J_k^T M and dM[f_k] both have it)."""
    return metric_degree + field_degree - 1


def margin_degree(W, mexps, fexps) -> int:
    """Degree of G_k for the numeric metric W: only the monomials W actually uses count.

    The learner's margin grows like |z| to this power (:func:`margin_matrix`)."""
    used = np.abs(W).max(axis=(0, 1)) > 0
    return contraction_degree(degree(mexps[used]), degree(fexps))


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
    N, n = Z.shape
    if degree(mexps) > 0:
        dM = eval_metric_gradient(W, mexps, Z).reshape(N, n, n * n)
        Mdot = (F @ dM).reshape(N, -1, n, n)                      # sum_l F[n,k,l] dM[n,l,a,b]
    else:
        Mdot = 0.0                                                # a constant metric: dM = 0
    JtM = np.swapaxes(J, -1, -2) @ M
    return JtM + np.swapaxes(JtM, -1, -2) + Mdot + gamma * M


def generalized_max_eig(G, M):
    """max_k lambda_max(M^-1/2 G_k M^-1/2) per sample; G (N, K, n, n), M (N, n, n)."""
    L = np.linalg.cholesky(M)
    Linv = np.linalg.inv(L)[:, None]
    S = Linv @ G @ np.swapaxes(Linv, -1, -2)
    return np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))[..., -1].max(axis=1)


def sample_states(seed: int, count: int, n: int) -> np.ndarray:
    """``count`` states drawn uniformly in the box |z|_inf <= SAMPLE_BOX (numpy Generator ``seed``)."""
    return np.random.default_rng(seed).uniform(-SAMPLE_BOX, SAMPLE_BOX, size=(int(count), n))


def sampled_eigenvalues(C, fexps, W, mexps, Z, gamma) -> tuple[float, float]:
    """(max over z in Z and k of the generalised eigenvalue of (G_k(z), M(z)), min eig of M(z)).

    Contraction at the samples means the first is <= 0 and the second > 0; the first is inf
    when M(z) is not positive definite somewhere (no generalised eigenvalue).

    For linear fields under a constant metric, J_k, M and so G_k do not depend on z: every
    state gives the same matrices, which are therefore computed at the first state only (the
    same numbers as at all of them, without 10^4 identical eigenvalue problems)."""
    if degree(fexps) == 1 and degree(mexps) == 0:
        Z = Z[:1]
    G = contraction_matrices(C, fexps, W, mexps, Z, gamma)
    M = eval_metric(W, mexps, Z)
    min_m = float(np.linalg.eigvalsh(M)[:, 0].min())
    max_g = float(generalized_max_eig(G, M).max()) if min_m > 0 else np.inf
    return max_g, min_m


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


def contraction_polymatrix(f, M, vars, gamma, scale=1.0):
    """scale * G(z), G = J^T M + M J + dM[f] + gamma M, as a PolyMatrix (f: list of n Polynomials).

    Computed on term arrays (:class:`~sosdyn.poly.termarrays.Terms`): J^T M is one join of the
    Jacobian's terms with M's on the inner index, dM[f] one join of dM/dz_l with f_l, and like
    terms are combined once for the whole matrix -- no loop over its n x n entries. ``scale=-1``
    gives -G exactly, keeping its term arrays for the SOS layer (unlike negating the matrix)."""
    vars = variable_names(vars)
    n = len(vars)
    ft, mt = matrix_terms(list(f), vars), M.terms(vars)
    JtM = terms_matmul(terms_transpose(terms_jacobian(ft, n)), mt)
    G = concat_terms(JtM, terms_transpose(JtM), terms_directional_derivative(mt, ft, n), terms_scale(mt, gamma))
    return PolyMatrix.from_terms(G if scale == 1.0 else terms_scale(G, scale), (n, n), vars)


def certificate_matrices(C, fexps, W, mexps, gamma, eps) -> list:
    """[(name, P)]: the polynomial matrices that must be SOS, in the certificate's order:
    M - eps I, then -G_k for k = 1..K."""
    vars, n = state_variables(W.shape[0]), W.shape[0]
    M = numeric_metric(W, mexps, vars)
    mats = [("M - eps I", M - eps * PolyMatrix.identity(n))]
    mats += [(f"-G[{k}]", contraction_polymatrix(f, M, vars, gamma, scale=-1.0))
             for k, f in enumerate(numeric_fields(C, fexps, vars))]
    return mats


def margin_matrix(vars, n, degree):
    """(1 + |z|^2)^(degree/2) I: a margin that also holds at infinity.

    A plain margin I leaves the top-degree part of -G_k on the boundary of the PSD cone, where
    no other factor can move; growing with the degree of G keeps every iterate interior.
    """
    growth = (1.0 + sum(Polynomial((v,), [[2]], [1.0]) for v in vars)) ** (degree // 2)
    return PolyMatrix.identity(n) * growth.with_vars(vars)


def unit_metrics(mexps, n, vars):
    """[((a, b, j), E)]: E has z^g_j at (a, b) and (b, a), so M = sum W[a, b, j] E.

    Each E is made from its one or two terms (:class:`~sosdyn.poly.termarrays.Terms`), not
    entry by entry."""
    vars = variable_names(vars)
    out = []
    for a, b in symmetric_pairs(n):
        rows, cols = np.array(sorted({a, b})), np.array(sorted({a, b}, reverse=True))
        for j in range(mexps.shape[0]):
            t = Terms(rows, cols, np.repeat(mexps[j:j + 1], rows.size, axis=0), np.full(rows.size, -1),
                      np.ones(rows.size))
            out.append(((a, b, j), PolyMatrix.from_terms(t, (n, n), vars)))
    return out


def field_jacobian(f, vars) -> PolyMatrix:
    """J_ij = d f_i / d z_j of the field f (a list of n Polynomials), on term arrays."""
    vars = variable_names(vars)
    return PolyMatrix.from_terms(terms_jacobian(matrix_terms(list(f), vars), len(vars)), (len(f), len(vars)), vars)


def unit_fields(fexps, n, vars):
    """[((i, j), f)]: the field with z^e_j in component i and zeros elsewhere."""
    zero = Polynomial.constant(0.0, vars)
    return [((i, j), [Polynomial(vars, fexps[j:j + 1], [1.0]) if r == i else zero for r in range(n)])
            for i in range(n) for j in range(fexps.shape[0])]

"""Gram matrices: the svec layout and the sparse coefficient-matching map.

A Gram matrix Q (size b) over the basis z(x) is stored as its scaled upper triangle,
column by column (Clarabel's PSD-triangle layout): s = (Q_00, sqrt2 Q_01, Q_11,
sqrt2 Q_02, ...). Then z^T Q z = sum_k w_k s_k x^(a_i + a_j) with w = 1 on the diagonal
and sqrt2 off it; grouping equal exponent sums (np.unique) gives one sparse matrix
G (monomials x svec) with coefficient(z^T Q z) = G s.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..poly.monomials import unique_rows

SQRT2 = np.sqrt(2.0)


def svec_pairs(b: int):
    """Row and column index (i <= j) of every svec entry, in Clarabel's order."""
    cols = np.repeat(np.arange(b), np.arange(1, b + 1))
    rows = np.concatenate([np.arange(j + 1) for j in range(b)]) if b else np.zeros(0, dtype=int)
    return rows.astype(np.int64), cols.astype(np.int64)


def svec_size(b: int) -> int:
    return b * (b + 1) // 2


def svec_to_matrix(s: np.ndarray, b: int) -> np.ndarray:
    """The symmetric matrix of an svec vector."""
    i, j = svec_pairs(b)
    Q = np.zeros((b, b))
    vals = np.where(i == j, s, s / SQRT2)
    Q[i, j] = vals
    Q[j, i] = vals
    return Q


def matrix_to_svec(Q: np.ndarray) -> np.ndarray:
    i, j = svec_pairs(Q.shape[0])
    return np.where(i == j, Q[i, j], SQRT2 * Q[i, j])


def gram_matching(basis: np.ndarray):
    """Monomials of z^T Q z and the sparse map G with coefficients = G @ svec(Q)."""
    b = basis.shape[0]
    i, j = svec_pairs(b)
    exps, inv = unique_rows(basis[i] + basis[j])
    weights = np.where(i == j, 1.0, SQRT2)
    G = sp.csr_matrix((weights, (inv, np.arange(i.size))), shape=(exps.shape[0], i.size))
    return exps, G

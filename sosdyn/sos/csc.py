"""Compressed sparse column (CSC) matrices made from arrays already in CSC order.

scipy's ``csc_matrix((data, indices, indptr))`` re-derives the index type and validates the
arrays on every call: about 40 µs whatever the size, and the conic form of a small SOS
program takes a dozen matrices, so on small programs those checks were most of the
canonicalisation. The functions here compute the CSC arrays with numpy (entries by column,
then by row, no duplicates: the canonical layout scipy itself produces) and :func:`csc` wraps
them without the checks. Whether scipy's matrix class accepts that wrapping is itself checked
once, at import, against the validating constructor; if it does not (another scipy), every
matrix goes through the validating constructor instead.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

_INT32_MAX = np.iinfo(np.int32).max


def _wrapped(data, indices, indptr, shape) -> sp.csc_matrix:
    M = sp.csc_matrix.__new__(sp.csc_matrix)
    M._shape, M.maxprint = shape, 50
    M.data, M.indices, M.indptr = data, indices, indptr
    M._has_sorted_indices = M._has_canonical_format = True     # what the caller promises (csc doc)
    return M


def _index_type(shape, nnz) -> type:
    return np.int32 if max(shape[0], shape[1], nnz) < _INT32_MAX else np.int64


def csc(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, shape: tuple) -> sp.csc_matrix:
    """The CSC matrix of canonical arrays (row ``indices`` sorted within each column, no duplicates)."""
    shape = (int(shape[0]), int(shape[1]))
    t = _index_type(shape, data.size)
    data = data if data.dtype == np.float64 else data.astype(float)
    if not _FAST:
        return sp.csc_matrix((data, indices.astype(t), indptr.astype(t)), shape=shape)
    return _wrapped(data, indices if indices.dtype == t else indices.astype(t),
                    indptr if indptr.dtype == t else indptr.astype(t), shape)


def column_of_entries(M: sp.csc_matrix) -> np.ndarray:
    """The column of every stored entry of a CSC matrix."""
    return np.repeat(np.arange(M.shape[1]), M.indptr[1:] - M.indptr[:-1])


def from_triplets(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, shape: tuple) -> sp.csc_matrix:
    """The CSC matrix with entries vals[k] at (rows[k], cols[k]); positions must be distinct."""
    order = np.lexsort((rows, cols))
    indptr = np.concatenate(([0], np.cumsum(np.bincount(cols, minlength=shape[1]))))
    return csc(vals[order], rows[order], indptr, shape)


def vstack(blocks: list, n: int) -> sp.csc_matrix:
    """[s_1 M_1; s_2 M_2; ...] for (M_k, s_k) pairs: CSC matrices with n columns, signs s_k."""
    blocks = [(M, sign) for M, sign in blocks if M.shape[0]]
    if len(blocks) == 1 and blocks[0][1] > 0:
        return blocks[0][0]
    rows, cols, vals, offset = [], [], [], 0
    for M, sign in blocks:
        rows.append(M.indices.astype(np.int64) + offset)
        cols.append(column_of_entries(M))
        vals.append(M.data if sign > 0 else -M.data)
        offset += M.shape[0]
    c = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    order = np.argsort(c, kind="stable")       # blocks in order, rows sorted within each block
    indptr = np.concatenate(([0], np.cumsum(np.bincount(c, minlength=n))))
    r = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    v = np.concatenate(vals) if vals else np.zeros(0)
    return csc(v[order], r[order], indptr, (offset, n))


def _wrapping_works() -> bool:
    """True if a wrapped matrix behaves as scipy's own on a small example (module doc)."""
    data, indices, indptr = np.array([1.0, -2.0, 3.0]), np.array([0, 2, 1], np.int32), np.array([0, 2, 2, 3], np.int32)
    try:
        fast, slow = _wrapped(data, indices, indptr, (3, 3)), sp.csc_matrix((data, indices, indptr), shape=(3, 3))
        x = np.array([1.0, 2.0, 3.0])
        return (np.array_equal(fast.toarray(), slow.toarray()) and np.array_equal(fast @ x, slow @ x)
                and fast.has_canonical_format and fast.has_sorted_indices
                and fast.nnz == slow.nnz and np.array_equal(sp.vstack([fast, slow]).toarray(),
                                                            sp.vstack([slow, slow]).toarray()))
    except Exception:  # noqa: BLE001 -- any failure means: use the validating constructor
        return False


_FAST = _wrapping_works()

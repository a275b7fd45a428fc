"""Monomial exponent arrays: the numeric core shared by every polynomial operation.

A polynomial in variables (v_1, ..., v_n) stores its monomials as an integer array E of
shape (m, n); row i is the exponent vector alpha_i of the monomial v^alpha_i.

Total degrees are at most ``MAX_DEGREE`` = 1000: 2^1000 ~ 1e301, so a monomial of higher
degree overflows float64 already at |v| = 2 and its values are meaningless in floating point.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import PolynomialError
from ..limits import check_bytes

_MAX_KEY = 2**62
MAX_DEGREE = 1000
CACHE_MAX_MONOMIALS = 4096   # monomials_up_to keeps answers up to C(n + degree, n) rows of this many
SMALL_ROWS = 64     # unique_rows / match_rows work on Python tuples up to this many rows (numpy's
                    # fixed cost per call is larger there than the work)


def monomial_keys(exps: np.ndarray, base: int | None = None) -> np.ndarray | None:
    """Encode exponent rows as int64 keys in mixed radix ``base`` (None if they overflow)."""
    m, n = exps.shape
    if base is None:
        base = int(exps.max()) + 1 if exps.size else 1
    if n == 0:
        return np.zeros(m, dtype=np.int64)
    if int(base) ** n >= _MAX_KEY:            # exact integers: a float power overflows for n > ~400
        return None
    weights = base ** np.arange(n - 1, -1, -1, dtype=np.int64)
    return exps.astype(np.int64, copy=False) @ weights


def wide_keys(exps: np.ndarray) -> np.ndarray | None:
    """int64 keys of exponent rows too wide for :func:`monomial_keys` (n variables, few of them
    in each monomial), ordered and equal as the rows are lexicographically; None if they overflow.

    Row i's nonzero entries (c, e), by column, become (n - c) E + e (E = max exponent + 1), padded
    with 0: at the first position where two rows differ, a smaller column (the other row is 0
    there) or a larger exponent gives the larger number -- dense lexicographic order, in a key
    as wide as the monomial's number of variables instead of n."""
    m, n = exps.shape
    r, c = np.nonzero(exps)
    per = np.bincount(r, minlength=m)
    E = int(exps.max(initial=0)) + 1
    pairs = np.zeros((m, int(per.max(initial=0))), dtype=np.int64)
    pairs[r, np.arange(r.size) - np.repeat(np.cumsum(per) - per, per)] = (n - c) * E + exps[r, c]
    return monomial_keys(pairs, n * E + E)


def _row_keys(exps: np.ndarray) -> np.ndarray | None:
    """:func:`monomial_keys`, else :func:`wide_keys` (None if both overflow)."""
    keys = monomial_keys(exps)
    return wide_keys(exps) if keys is None else keys


def unique_rows(exps: np.ndarray):
    """Unique exponent rows (sorted lexicographically) and the inverse index of every row."""
    if exps.shape[0] == 0:
        return exps.reshape(0, exps.shape[1]), np.zeros(0, dtype=np.int64)
    if exps.shape[0] <= SMALL_ROWS:            # plain Python: tuples sort lexicographically
        rows = [tuple(r) for r in exps.tolist()]
        uniq = sorted(set(rows))
        at = {r: i for i, r in enumerate(uniq)}
        return (np.array(uniq, dtype=exps.dtype).reshape(len(uniq), exps.shape[1]),
                np.array([at[r] for r in rows], dtype=np.int64))
    keys = _row_keys(exps)
    if keys is None:
        return _unique_wide_rows(exps)
    _, first, inv = np.unique(keys, return_index=True, return_inverse=True)
    return exps[first], inv.ravel()


_HASH_WEIGHTS = np.random.default_rng(20261126).integers(1, 2**62, size=4096) | 1


def _row_hashes(exps: np.ndarray) -> np.ndarray:
    """exps @ odd random int64 weights, wrapping: equal rows, equal hashes (the converse is
    checked by the callers)."""
    k = np.arange(exps.shape[1])
    w = _HASH_WEIGHTS[k % _HASH_WEIGHTS.size] * (1 + k // _HASH_WEIGHTS.size)
    with np.errstate(over="ignore"):
        return exps.astype(np.int64) @ w


def _unique_wide_rows(exps: np.ndarray):
    """:func:`unique_rows` for rows too wide for one int64 key (hundreds of variables): rows
    grouped by a hash (exps @ odd random weights, wrapping int64), each group's rows compared
    in full (a collision falls back to numpy's row sort), the distinct rows then put in
    lexicographic order -- O(rows x columns) instead of numpy's sort of wide rows."""
    h = _row_hashes(exps)
    order = np.argsort(h, kind="stable")
    same = h[order][1:] == h[order][:-1]
    if same.any() and (exps[order[1:][same]] != exps[order[:-1][same]]).any():
        uniq, inv = np.unique(exps, axis=0, return_inverse=True)      # a hash collision
        return uniq, inv.ravel()
    group = np.concatenate(([0], np.cumsum(~same)))
    first = order[np.flatnonzero(np.concatenate(([True], ~same)))]
    lex = np.lexsort(exps[first].T[::-1]) if exps.shape[0] * exps.shape[1] <= 2**24 else \
        np.lexsort([exps[first, c] for c in range(exps.shape[1] - 1, -1, -1)])   # column by column
    rank = np.empty_like(lex)
    rank[lex] = np.arange(lex.size)
    inv = np.empty(exps.shape[0], dtype=np.int64)
    inv[order] = rank[group]
    return exps[first[lex]], inv


def sum_rows(exps: np.ndarray, coef: np.ndarray):
    """Combine like monomials: unique exponent rows and the summed coefficient rows."""
    if exps.shape[0] == 0:
        return exps, coef
    keys = _row_keys(exps)
    if keys is not None:                       # fast path: one sort of int64 keys
        order = np.argsort(keys, kind="stable")
        sk = keys[order]
        starts = np.flatnonzero(np.concatenate(([True], sk[1:] != sk[:-1])))
        if starts.size == keys.size:           # no like terms: a sort
            return exps[order], coef[order]
        return exps[order[starts]], np.add.reduceat(coef[order], starts, axis=0)
    uniq, inv = unique_rows(exps)
    order = np.argsort(inv, kind="stable")
    sorted_inv = inv[order]
    if sorted_inv.size == 0:
        return uniq, coef[:0]
    starts = np.flatnonzero(np.r_[True, sorted_inv[1:] != sorted_inv[:-1]])
    return uniq, np.add.reduceat(coef[order], starts, axis=0)


def combine_terms(exps: np.ndarray, coef: np.ndarray, ids: np.ndarray, sort: bool = True):
    """Canonical terms: like monomials summed (and rows sorted) when ``sort``, terms whose
    coefficient row is all zero dropped, decision ids no coefficient uses dropped."""
    if sort and exps.shape[0] > 1:
        exps, coef = sum_rows(exps, coef)
    nonzero = coef != 0.0
    keep = nonzero.any(axis=1)
    if not keep.all():
        exps, coef, nonzero = exps[keep], coef[keep], nonzero[keep]
    if ids.size:
        used = nonzero[:, 1:].any(axis=0)
        if not used.all():
            coef, ids = coef[:, np.concatenate(([True], used))], ids[used]
    return exps, coef, ids


def monomials_up_to(n: int, degree: int, min_degree: int = 0,
                    max_per_var: np.ndarray | None = None) -> np.ndarray:
    """All exponent vectors in n variables with min_degree <= |alpha| <= degree.

    ``max_per_var`` optionally caps each variable's exponent. Rows are ordered by total
    degree, then lexicographically (graded order). There are at most C(n + degree, n) of
    them; their size is checked against ``sosdyn.limits`` before they are built.
    """
    if degree < 0 or degree < min_degree:
        return np.zeros((0, n), dtype=np.int64)
    if degree > MAX_DEGREE:
        raise PolynomialError(f"degree {degree} is above {MAX_DEGREE} (see sosdyn.poly.monomials). "
                              "Try: a lower degree")
    if n == 0:
        return np.zeros((1 if min_degree <= 0 else 0, 0), dtype=np.int64)
    count = math.comb(n + degree, n)
    check_bytes(3 * 8.0 * n * count,           # the rows, sort keys, sorted copy
                f"the monomials of degree <= {degree} in {n} variables",
                "lower the degree or the number of variables")
    if max_per_var is None and count <= CACHE_MAX_MONOMIALS:     # a program asks for the same few many times
        return _monomials_cached(int(n), int(degree), int(min_degree)).copy()
    return _monomials(n, degree, min_degree, max_per_var)


@functools.lru_cache(maxsize=256)
def _monomials_cached(n: int, degree: int, min_degree: int) -> np.ndarray:
    return _monomials(n, degree, min_degree, None)


def _monomials(n: int, degree: int, min_degree: int, max_per_var) -> np.ndarray:
    """The rows of :func:`monomials_up_to` (arguments checked there)."""
    caps = np.full(n, degree) if max_per_var is None else np.minimum(max_per_var, degree)
    arr, used = np.zeros((1, 0), dtype=np.int64), np.zeros(1, dtype=np.int64)
    for cap in caps:             # row r of the prefix gets exponents 0..min(cap, degree - used_r)
        counts = np.maximum(np.minimum(cap, degree - used) + 1, 0)
        starts = np.cumsum(counts) - counts
        e = np.arange(counts.sum()) - np.repeat(starts, counts)
        arr = np.column_stack([np.repeat(arr, counts, axis=0), e])
        used = np.repeat(used, counts) + e
    arr = arr[used >= min_degree]
    if not arr.shape[0]:
        return np.zeros((0, n), dtype=np.int64)
    order = np.lexsort(tuple(-arr[:, i] for i in range(n - 1, -1, -1)) + (arr.sum(1),))
    return arr[order]


def match_rows(table: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """Index of each query row in ``table`` (rows unique), -1 where absent."""
    if queries.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    if table.shape[0] == 0:
        return np.full(queries.shape[0], -1, dtype=np.int64)
    if table.shape[0] + queries.shape[0] <= SMALL_ROWS:      # plain Python: a dict of rows
        lookup = {tuple(r): i for i, r in enumerate(table.tolist())}
        return np.array([lookup.get(tuple(r), -1) for r in queries.tolist()], dtype=np.int64)
    base = int(max(table.max(initial=0), queries.max(initial=0))) + 1
    tk = monomial_keys(table, base)
    qk = monomial_keys(queries, base)
    if tk is None:                            # wide rows: hashes, each hit compared in full
        tk, qk = _row_hashes(table), _row_hashes(queries)
        order = np.argsort(tk)
        if (tk[order][1:] == tk[order][:-1]).any():          # a collision among the table's rows
            lookup = {tuple(r): i for i, r in enumerate(table.tolist())}
            return np.array([lookup.get(tuple(r), -1) for r in queries.tolist()], dtype=np.int64)
        pos = np.clip(np.searchsorted(tk[order], qk), 0, len(tk) - 1)
        hit = order[pos]
        found = (tk[hit] == qk) & (table[hit] == queries).all(axis=1)
        return np.where(found, hit, -1)
    order = np.argsort(tk)
    pos = np.searchsorted(tk[order], qk)
    pos = np.clip(pos, 0, len(tk) - 1)
    found = tk[order][pos] == qk
    return np.where(found, order[pos], -1)


def multiset_keys(exps: np.ndarray, cols: np.ndarray, width: int) -> np.ndarray:
    """Row r: cols[c] + 1 repeated exps[r, c] times over c (``cols`` ascending, so sorted),
    padded with zeros to ``width`` columns: a monomial by its variables, free of the total
    number of variables."""
    r, c = np.nonzero(exps)
    reps = exps[r, c]
    rows = np.repeat(r, reps)
    deg = np.bincount(rows, minlength=exps.shape[0])
    at = np.arange(rows.size) - np.repeat(np.cumsum(deg) - deg, deg)
    out = np.zeros((exps.shape[0], width), dtype=np.int64)
    out[rows, at] = np.repeat(np.asarray(cols, dtype=np.int64)[c], reps) + 1
    return out


def keys_to_exps(keys: np.ndarray, n: int) -> np.ndarray:
    """The exponent rows over n variables of :func:`multiset_keys` rows."""
    out = np.zeros((keys.shape[0], n + 1), dtype=np.int64)
    np.add.at(out, (np.repeat(np.arange(keys.shape[0]), keys.shape[1]), keys.ravel()), 1)
    return out[:, 1:]

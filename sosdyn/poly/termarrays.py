"""Polynomial matrices as flat term arrays: the vectorised form of their arithmetic.

A 2-D array of Polynomials (a PolyMatrix's entries) becomes one :class:`Terms`: term t adds
val[t] * d[did[t]] * x^exps[t] to entry (row[t], col[t]) (did = -1: no decision variable).
Products are joins on the inner index (:func:`term_pairs`), derivatives act on the exponent
column, and like terms are combined once, at the end, by one sort (:func:`combine`), so no
operation loops over the entries of an n x n matrix of polynomials. The results are the
canonical Polynomials entry-by-entry arithmetic gives (same monomial order, same decision
ids, coefficients equal up to the order of floating-point sums).
"""
from __future__ import annotations

from numbers import Number
from typing import NamedTuple

import numpy as np

from ..errors import PolynomialError
from .checks import check_coefficients, check_terms_size, real_array
from .monomials import monomial_keys, unique_rows
from .polynomial import Polynomial


class Terms(NamedTuple):
    """Flat term arrays of a polynomial matrix (module docstring)."""

    row: np.ndarray
    col: np.ndarray
    exps: np.ndarray
    did: np.ndarray
    val: np.ndarray

    def select(self, idx) -> "Terms":
        return Terms(*(a[idx] for a in self))


def concat_terms(*parts: Terms) -> Terms:
    return Terms(*(np.concatenate(arrays) for arrays in zip(*parts)))


def _arrays(p, vars):
    """(exps over ``vars``, coef, ids) of an entry (a Polynomial or a number)."""
    if isinstance(p, Polynomial):
        if p.vars == vars:
            return p.exps, p.coef, p.ids
        if not p.vars:
            return np.zeros((p.nterms, len(vars)), dtype=np.int64), p.coef, p.ids
        q = p.with_vars(vars)
        return q.exps, q.coef, q.ids
    if isinstance(p, Number) or (isinstance(p, np.ndarray) and p.ndim == 0):
        return np.zeros((1, len(vars)), dtype=np.int64), real_array(p, "a matrix entry").reshape(1, 1), \
            np.zeros(0, dtype=np.int64)
    raise PolynomialError(f"matrix entry {p!r} is neither a number nor a Polynomial")


def matrix_terms(entries, vars) -> Terms:
    """The terms of a 2-D array of Polynomials or numbers (a 1-D one is a column) over ``vars``.

    One pass over the entries collects their arrays; the nonzero coefficients are then found
    and indexed at once (no per-entry numpy work)."""
    entries = np.asarray(entries, dtype=object)
    entries = entries.reshape(-1, 1) if entries.ndim == 1 else entries
    arrays = [_arrays(p, vars) for p in entries.flat]
    rows = np.array([c.shape[0] for _, c, _ in arrays], dtype=np.int64)
    width = np.array([c.shape[1] for _, c, _ in arrays], dtype=np.int64)
    sizes = rows * width
    vals = np.concatenate([c.ravel() for _, c, _ in arrays] + [np.zeros(0)])
    entry = np.repeat(np.arange(len(arrays)), sizes)
    local = np.arange(vals.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    keep = vals != 0.0
    entry, local, vals = entry[keep], local[keep], vals[keep]
    r, j = local // width[entry], local % width[entry]
    exps = np.concatenate([e for e, _, _ in arrays] + [np.zeros((0, len(vars)), np.int64)])
    ids = np.concatenate([i for _, _, i in arrays] + [np.full(1, -1, np.int64)]).astype(np.int64)
    at = np.where(j > 0, (np.cumsum(width - 1) - (width - 1))[entry] + j - 1, ids.size - 1)   # j = 0: -1
    cols = entries.shape[1]
    return Terms(entry // cols, entry % cols, exps[(np.cumsum(rows) - rows)[entry] + r], ids[at], vals)


def terms_diff(t: Terms, j: int) -> Terms:
    """d/dx_j of every term: x^e -> e_j x^(e - unit_j) (terms with e_j = 0 vanish)."""
    t = t.select(t.exps[:, j] > 0)
    exps = t.exps.copy()
    exps[:, j] -= 1
    return t._replace(exps=exps, val=t.val * t.exps[:, j])


def term_pairs(akey: np.ndarray, bkey: np.ndarray, nvars: int):
    """All index pairs (ia, ib) with akey[ia] == bkey[ib] (non-negative int keys): a join."""
    order = np.argsort(bkey, kind="stable")
    counts = np.bincount(bkey, minlength=int(akey.max(initial=-1)) + 1)
    starts = np.cumsum(counts) - counts
    per_a = counts[akey]
    total = int(per_a.sum())
    check_terms_size(total, nvars, 4, "a polynomial matrix product")
    ia = np.repeat(np.arange(akey.size), per_a)
    ib = order[starts[akey[ia]] + np.arange(total) - np.repeat(np.cumsum(per_a) - per_a, per_a)]
    return ia, ib


def pair_products(a: Terms, ia, b: Terms, ib, row, col) -> Terms:
    """Terms a[ia] * b[ib] at entries (row, col). They stay affine in the decision variables: a
    pair of two decision terms is a PolynomialError (a bilinear term), as for Polynomial products."""
    da, db = a.did[ia], b.did[ib]
    if np.any((da >= 0) & (db >= 0)):
        raise PolynomialError("product of two polynomials that both depend on decision variables is "
                              "not affine in them (a bilinear term); fix one factor to numbers first")
    return Terms(row, col, a.exps[ia] + b.exps[ib], np.maximum(da, db), a.val[ia] * b.val[ib])


def terms_matmul(a: Terms, b: Terms) -> Terms:
    """The terms of A @ B: (A B)_rc = sum_i A_ri B_ic."""
    ia, ib = term_pairs(a.col, b.row, a.exps.shape[1])
    return pair_products(a, ia, b, ib, a.row[ia], b.col[ib])


def terms_transpose(t: Terms) -> Terms:
    return t._replace(row=t.col, col=t.row)


def terms_scale(t: Terms, s: float) -> Terms:
    return t._replace(val=t.val * float(s))


def terms_jacobian(f: Terms, nvars: int) -> Terms:
    """J_ij = d f_i / d x_j of a column vector f (its terms have col = 0)."""
    parts = [terms_diff(f, j) for j in range(nvars)]
    return concat_terms(*(p._replace(col=np.full(p.row.size, j)) for j, p in enumerate(parts)))


def terms_directional_derivative(m: Terms, f: Terms, nvars: int) -> Terms:
    """dM[f] = sum_l (dM/dx_l) f_l entry-wise, for a column vector f (terms with col = 0)."""
    parts = [terms_diff(m, l) for l in range(nvars)]
    dm = concat_terms(*parts)
    ia, ib = term_pairs(np.repeat(np.arange(nvars), [p.row.size for p in parts]), f.row, nvars)
    return pair_products(dm, ia, f, ib, dm.row[ia], dm.col[ia])


def combine(t: Terms):
    """Like terms summed and zeros dropped, sorted by (row, col, monomial, did): (Terms, keys),
    keys[t] a sort key of the monomial exps[t] (lexicographic order)."""
    keys = monomial_keys(t.exps) if t.exps.size else np.zeros(t.row.size, dtype=np.int64)
    if keys is None:
        keys = unique_rows(t.exps)[1]
    order = np.lexsort((t.did, keys, t.col, t.row))
    t, keys = t.select(order), keys[order]
    if not t.row.size:
        return t, keys
    new = np.r_[True, (np.diff(t.row) != 0) | (np.diff(t.col) != 0) | (np.diff(keys) != 0) | (np.diff(t.did) != 0)]
    starts = np.flatnonzero(new)
    val = np.add.reduceat(t.val, starts)
    keep = starts[val != 0.0]
    return t.select(keep)._replace(val=val[val != 0.0]), keys[keep]


def terms_entries(t: Terms, shape, vars) -> np.ndarray:
    """Combine like terms (:func:`combine`) and return the 2-D object array of canonical Polynomials.

    Entries list their monomials in :func:`~.monomials.sum_rows` order (lexicographic) and drop
    zero coefficients and unused decision ids, as a Polynomial built term by term would."""
    t, keys, vars = *combine(t), tuple(vars)
    check_coefficients(t.val)                               # once for every entry (sums can overflow)
    flat = t.row * shape[1] + t.col
    size = shape[0] * shape[1]
    bounds = np.searchsorted(flat, np.arange(size + 1))
    mono = np.r_[True, (np.diff(flat) != 0) | (np.diff(keys) != 0)] if flat.size else np.zeros(0, dtype=bool)
    row = np.cumsum(mono) - 1                              # monomial row, counted over all entries
    dec = t.did >= 0                                        # decision columns: rank of did in its entry
    base = int(t.did.max(initial=0)) + 1
    upair, rank = np.unique(flat[dec] * base + t.did[dec], return_inverse=True)
    ufirst = np.searchsorted(upair // base, np.arange(size + 1))
    cols = np.zeros(flat.size, dtype=np.int64)
    cols[dec] = 1 + rank.ravel() - ufirst[flat[dec]]
    uids = upair % base
    out = np.empty(shape, dtype=object)
    zero = Polynomial(vars, np.zeros((0, len(vars)), dtype=np.int64), np.zeros((0, 1)), canonical=True)
    for e in np.flatnonzero(bounds[1:] == bounds[:-1]):
        out[divmod(int(e), shape[1])] = zero                # polynomials are never changed in place
    for e in np.flatnonzero(bounds[1:] > bounds[:-1]):
        lo, hi = bounds[e], bounds[e + 1]
        ids = uids[ufirst[e]:ufirst[e + 1]]
        r = row[lo:hi] - row[lo]
        coef = np.zeros((int(r[-1]) + 1, 1 + ids.size))
        coef[r, cols[lo:hi]] = t.val[lo:hi]
        out[divmod(int(e), shape[1])] = Polynomial._bare(vars, t.exps[lo:hi][mono[lo:hi]], coef, ids)
    return out

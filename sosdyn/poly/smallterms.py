"""Arithmetic on small polynomials in plain Python: the fast path of Polynomial's operators.

A numpy call costs about a microsecond whatever the size of its arrays, and an operation on
a polynomial's arrays takes a dozen of them (align, stack, encode, sort, reduce, check);
for small operands (:func:`fits`) the same arithmetic on tuples and floats is several times faster.
The functions here take the arrays of admissible polynomials (:mod:`.polynomial`) and return
the canonical arrays :func:`.monomials.combine_terms` makes from the same terms:

* like monomials summed in the order they occur (the order of the array path's stable sort;
  numpy groups a sum of three or more like terms differently, so such a coefficient can differ
  from the array path's in the last bits),
* rows in lexicographic order of their exponents (the order of :func:`.monomials.monomial_keys`),
* all-zero coefficient rows and decision ids no coefficient uses dropped;

then the coefficients are checked (:func:`.checks.check_coefficients`), which arithmetic can
overflow. Exponent rows are tuples over the result's variables, coefficient rows lists over
(1, the result's decision ids).
"""
from __future__ import annotations

from operator import add as _add

import numpy as np

from .checks import MAX_COEFFICIENT, check_coefficients, check_degree

# The Python path serves operations on at most this many cells (terms before combining x (1 +
# coefficient columns)); above, numpy's fixed cost is the smaller one (measured: a sum of 16 terms
# with 4 columns 45 us here vs 104 us on arrays, of 12 terms with 31 columns 237 vs 105 us).
SMALL_CELLS = 160
SMALL_PRODUCT_CELLS = 64     # the same for products (a Python loop over every pair of terms)
NO_IDS = np.zeros(0, dtype=np.int64)     # the decision ids of numeric polynomials, shared (read-only)
NO_IDS.flags.writeable = False


def fits(terms: int, columns: int, cells: int | None = None) -> bool:
    """True if an operation on ``terms`` terms of ``columns`` coefficient columns takes the Python path."""
    return terms * (1 + columns) <= (SMALL_CELLS if cells is None else cells)


def terms(vars: tuple, exps: np.ndarray, coef: np.ndarray, ids: list, to_vars: tuple, to_ids: list) -> list:
    """(exponent tuple over ``to_vars``, coefficient list over (1, ``to_ids``)) of every row.

    ``to_vars`` contains every variable of ``vars`` and ``to_ids`` every id of ``ids``.
    """
    if vars == to_vars:
        rows = [tuple(r) for r in exps.tolist()]
    else:
        at = [to_vars.index(v) for v in vars]
        rows = []
        for r in exps.tolist():
            e = [0] * len(to_vars)
            for j, k in zip(at, r):
                e[j] = k
            rows.append(tuple(e))
    cs = coef.tolist()
    if ids != to_ids:
        at = [1 + to_ids.index(d) for d in ids]
        wide = []
        for c in cs:
            w = [0.0] * (1 + len(to_ids))
            w[0] = c[0]
            for j, v in zip(at, c[1:]):
                w[j] = v
            wide.append(w)
        cs = wide
    return list(zip(rows, cs))


def canonical(acc: dict, nvars: int, ids: list, ids_array: np.ndarray):
    """(exps, coef, ids) arrays of summed terms ``acc`` {exponent tuple: coefficient list} (module
    doc); ``ids_array`` is ``ids`` as an array, returned when every id stays."""
    keys = sorted([k for k, c in acc.items() if any(c)])
    if not keys:
        return np.zeros((0, nvars), dtype=np.int64), np.zeros((0, 1)), NO_IDS
    rows = [acc[k] for k in keys]
    if ids:
        used = [j for j in range(1, 1 + len(ids)) if any([r[j] for r in rows])]  # noqa: C419 -- lists are
        # faster than generators at these sizes
        if len(used) < len(ids):
            rows = [[r[0]] + [r[j] for j in used] for r in rows]
            ids_array = np.array([ids[j - 1] for j in used], dtype=np.int64)
    coef = np.array(rows, dtype=float)
    if not all([abs(v) <= MAX_COEFFICIENT for r in rows for v in r]):  # noqa: C419 -- False for NaN too
        check_coefficients(coef)
    return np.array(keys, dtype=np.int64) if nvars else np.zeros((len(keys), 0), dtype=np.int64), coef, ids_array


def combine(exps: np.ndarray, coef: np.ndarray, ids: np.ndarray):
    """The canonical arrays of the terms (rows of ``exps``, ``coef``) over decision ids ``ids``."""
    acc: dict = {}
    for e, c in zip(map(tuple, exps.tolist()), coef.tolist()):
        prev = acc.get(e)
        acc[e] = c if prev is None else [u + v for u, v in zip(prev, c)]
    return canonical(acc, exps.shape[1], ids.tolist(), ids)


def add(a, b, sign: float, vars: tuple):
    """Arrays of a + sign * b (sign 1 or -1) over ``vars``; ``a``, ``b`` have a polynomial's
    ``vars``, ``exps``, ``coef`` and ``ids``."""
    ia, ib = a.ids.tolist(), b.ids.tolist()
    if ia == ib or not ib:
        ids, ids_array = ia, a.ids
    elif not ia:
        ids, ids_array = ib, b.ids
    else:
        ids = sorted(set(ia) | set(ib))
        ids_array = np.array(ids, dtype=np.int64)
    acc = {}
    for e, c in terms(a.vars, a.exps, a.coef, ia, vars, ids):
        acc[e] = c
    for e, c in terms(b.vars, b.exps, b.coef, ib, vars, ids):
        if sign < 0:
            c = [-v for v in c]
        prev = acc.get(e)
        acc[e] = c if prev is None else [u + v for u, v in zip(prev, c)]
    return canonical(acc, len(vars), ids, ids_array)


def multiply(a, b, vars: tuple):
    """Arrays of a * b over ``vars`` for a numeric ``b`` (``a``, ``b`` as in :func:`add`)."""
    ids = a.ids.tolist()
    acc: dict = {}
    left = terms(a.vars, a.exps, a.coef, ids, vars, ids)
    right = [(e, c[0]) for e, c in terms(b.vars, b.exps, b.coef, [], vars, [])]
    if left and right:          # the product's degree is checked before its terms are made
        check_degree(max(map(sum, (e for e, _ in left))) + max(sum(e) for e, _ in right), "a product")
    for ea, ca in left:
        for eb, cb in right:
            e = tuple(map(_add, ea, eb))
            c = [v * cb for v in ca]
            prev = acc.get(e)
            acc[e] = c if prev is None else [u + v for u, v in zip(prev, c)]
    return canonical(acc, len(vars), ids, a.ids)


def scale(exps: np.ndarray, coef: np.ndarray, ids: np.ndarray, s: float):
    """Arrays of s * p (terms that underflow to zero dropped)."""
    nvars = exps.shape[1]
    acc = {tuple(e): [v * s for v in c] for e, c in zip(exps.tolist(), coef.tolist())}
    return canonical(acc, nvars, ids.tolist(), ids)


def power(exps: np.ndarray, coef: np.ndarray, ids: np.ndarray, k: int):
    """Arrays of (c x^a)^k = c^k x^(k a) for a one-term numeric polynomial (degree checked first)."""
    e = tuple(v * k for v in exps[0].tolist())
    check_degree(sum(e), f"a power p**{k}")
    try:
        c = coef[0, 0].item() ** k
    except OverflowError:                       # refused by the coefficient check
        c = float("inf")
    return canonical({e: [c]}, len(e), [], ids)

"""The identity of an SOS constraint as arrays, its evaluation at a point, and its faces.

For "source >= 0 on K" with Gram blocks Q_k (the main one and a sparse constraint's clique
blocks), SOS multipliers sigma_i = z_i^T S_i z_i of g_i >= 0 and free multipliers lambda_j of
h_j = 0, every term of

    e = source - sum_i sigma_i g_i - sum_j lambda_j h_j - sum_k z_k^T Q_k z_k        (*)

is a product of at most three floats (:class:`Identity`); :func:`residual` sums them with a bound
on the rounding, :func:`exact_residual` in rational arithmetic. :func:`faces` lists the kept-row
masks the judge (:mod:`.proof`) tries: rows every certificate sets to zero, rows whose square the
polynomial does not reach, rows of tiny diagonal.
"""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..poly import multiset_keys, unique_rows
from .gram import svec_pairs, svec_to_matrix
from .sets import BasicSet, variable_bounds

EPS = np.finfo(float).eps
UNIT = EPS / 2
FACES = (1e-9, 1e-7, 1e-5)   # relative Gram diagonals below which a row leaves the face (heuristic faces)


def gam(k):
    """gamma_k = k u / (1 - k u): the relative error bound of k floating-point operations."""
    ku = np.asarray(k, dtype=float) * UNIT
    return ku / (1.0 - ku)


# ---------------------------------------------------------------------- the identity's structure
def exps_over(basis, vars) -> np.ndarray:
    """A basis's exponent rows over ``vars`` (zeros for the variables it does not use)."""
    out = np.zeros((len(basis), len(vars)), dtype=np.int64)
    out[:, columns_of(vars, basis.vars)] = basis.exps
    return out


def columns_of(vars, sub) -> np.ndarray:
    at = {v: i for i, v in enumerate(vars)}
    return np.array([at[v] for v in sub], dtype=np.int64)


@dataclass
class Identity:
    """The terms of (*) for one constraint, as arrays (values are read at each point).

    Every term is ``c1 * c2 * factor`` on monomial ``mon`` (an index into the union of
    monomials, keyed by :func:`~sosdyn.poly.multiset_keys`); ``factor`` is 1 (kind 0),
    a decision value (kind 1, ``where`` = its id) or a Gram/multiplier matrix entry (kind 2,
    ``where`` = its index in the entry vector: the svec-ordered entries Q_ij, i <= j, of the
    blocks in ``blocks`` order, Gram blocks first). ``pair_mon[k]`` is the monomial of each
    svec pair of Gram block k; ``square[k]`` that of each diagonal pair."""

    mon: np.ndarray
    c1: np.ndarray
    c2: np.ndarray
    kind: np.ndarray
    where: np.ndarray
    count: np.ndarray            # terms per monomial
    blocks: list                 # (PsdBlock, size, offset into the entry vector, is Gram block)
    pair_mon: list
    n_mon: int
    source_rows: np.ndarray      # the term range of the source polynomial's coefficients
    other_terms: np.ndarray      # per monomial: terms that are not Gram-block terms
    source_mask: np.ndarray      # the source coefficients (rows, 1 + ids) these terms cover
    source_rc: tuple             # their (row, column), in term order
    keys: np.ndarray             # the union of monomials (multiset keys)
    radius: np.ndarray | None    # |x_i| <= radius_i on the constraint's set (None: not bounded)


def _keys(exps, cols, width):
    return multiset_keys(exps, cols, width)


def build_identity(con) -> Identity:
    """The :class:`Identity` of ``con`` (see the module docstring, (*))."""
    vars = con.basis.vars
    src = con.source.with_vars(vars)
    grams = con.gram_blocks
    mults = [m for m in con.multipliers if m.psd.role != "clique"]
    eqm = con.eq_multipliers
    degs = [int(src.exps.sum(axis=1).max(initial=0))]
    degs += [2 * int(b.exps.sum(axis=1).max(initial=0)) for b, _ in grams]
    degs += [2 * int(m.basis.exps.sum(axis=1).max(initial=0)) + m.constraint.degree for m in mults]
    degs += [m.poly.degree + m.constraint.degree for m in eqm]
    width = max(degs + [1])
    keys, c1, c2, kind, where = [], [], [], [], []

    def add(k, a, b, kd, w):
        keys.append(k)
        c1.append(np.asarray(a, dtype=float))
        c2.append(np.asarray(b, dtype=float))
        kind.append(np.full(len(k), kd, dtype=np.int8))
        where.append(np.asarray(w, dtype=np.int64))

    all_cols = np.arange(len(vars))
    skeys = _keys(src.exps, all_cols, width)
    rs, cs = np.nonzero(src.coef)
    add(skeys[rs], src.coef[rs, cs], np.ones(rs.size), np.where(cs == 0, 0, 1),
        np.where(cs == 0, -1, src.ids[np.maximum(cs - 1, 0)] if src.ids.size else -1))
    n_source = len(keys[0])
    blocks, pair_mon_keys, offset = [], [], 0
    for basis, psd in grams:
        i, j = svec_pairs(psd.size)
        k = _keys(basis.exps[i] + basis.exps[j], columns_of(vars, basis.vars), width)
        add(k, np.where(i == j, -1.0, -2.0), np.ones(i.size), 2, offset + np.arange(i.size))
        pair_mon_keys.append(k)
        blocks.append((psd, psd.size, offset, True))
        offset += i.size
    n_gram_terms = sum(len(k) for k in keys)
    for m in mults:
        i, j = svec_pairs(m.psd.size)
        g = m.constraint.with_vars(vars)
        B = np.zeros((len(m.basis), len(vars)), dtype=np.int64)
        B[:, columns_of(vars, m.basis.vars)] = m.basis.exps
        pairs = (B[i] + B[j])[:, None, :] + g.exps[None, :, :]
        k = _keys(pairs.reshape(-1, len(vars)), all_cols, width)
        w = np.where(i == j, -1.0, -2.0)[:, None] * np.ones(g.nterms)[None, :]
        gc = np.ones(i.size)[:, None] * g.coef[:, 0][None, :]
        add(k, w.ravel(), gc.ravel(), 2, (offset + np.arange(i.size))[:, None].repeat(g.nterms, 1).ravel())
        blocks.append((m.psd, m.psd.size, offset, False))
        offset += i.size
    for m in eqm:
        lam, h = m.poly.with_vars(vars), m.constraint.with_vars(vars)
        r, c = np.nonzero(lam.coef)
        exps = (lam.exps[r][:, None, :] + h.exps[None, :, :]).reshape(-1, len(vars))
        cc = (-lam.coef[r, c])[:, None] * np.ones(h.nterms)[None, :]
        hh = np.ones(r.size)[:, None] * h.coef[:, 0][None, :]
        ids = np.where(c == 0, -1, lam.ids[np.maximum(c - 1, 0)] if lam.ids.size else -1)
        add(_keys(exps, all_cols, width), cc.ravel(), hh.ravel(), 0, ids[:, None].repeat(h.nterms, 1).ravel())
        kind[-1] = np.where(np.repeat(c, h.nterms) == 0, 0, 1).astype(np.int8)
    allkeys = np.vstack(keys) if keys else np.zeros((0, width), dtype=np.int64)
    U, inv = unique_rows(allkeys)
    inv = np.asarray(inv).ravel()
    n_mon = U.shape[0]
    starts = np.cumsum([0] + [len(k) for k in keys])
    pair_mon = []
    for kb in range(len(grams)):
        pair_mon.append(inv[starts[1 + kb]:starts[2 + kb]])
    other = np.ones(inv.size, dtype=bool)
    other[n_source:n_gram_terms] = False
    mask = np.zeros(src.coef.shape, dtype=bool)
    mask[rs, cs] = True
    K = BasicSet(ineqs=[m.constraint for m in mults], eqs=[m.constraint for m in eqm])
    radius = variable_bounds(K, vars) if K.ineqs or K.eqs else None
    return Identity(inv, np.concatenate(c1), np.concatenate(c2), np.concatenate(kind), np.concatenate(where),
                    np.bincount(inv, minlength=n_mon), blocks, pair_mon, n_mon, np.arange(n_source),
                    np.bincount(inv[other], minlength=n_mon), mask, (rs, cs), U, radius)


_IDENTITIES: OrderedDict = OrderedDict()
_KEPT = 128


def identity_of(con) -> Identity:
    """:func:`build_identity`, remembered while the constraint's monomials, blocks and the pattern
    of its non-zero source coefficients stay (a family re-solved with new weights keeps its
    arrays); the source's coefficients themselves are read now (:func:`current`)."""
    src = con.source.with_vars(con.basis.vars)
    parts = (src.exps, src.ids, *[psd for _, psd in con.gram_blocks], *[m.psd for m in con.multipliers],
             *[m.poly for m in con.eq_multipliers])
    key = id(con)
    hit = _IDENTITIES.get(key)
    if hit is not None and hit[0] is con and len(hit[1]) == len(parts) and all(map(_same, hit[1], parts)) \
            and hit[2].source_mask.shape == src.coef.shape and not ((src.coef != 0) & ~hit[2].source_mask).any():
        _IDENTITIES.move_to_end(key)
        return current(hit[2], src)
    out = build_identity(con)
    _IDENTITIES[key] = (con, parts, out)
    if len(_IDENTITIES) > _KEPT:
        _IDENTITIES.popitem(last=False)
    return out


def _same(a, b) -> bool:
    """The same object, or equal arrays (a family's new weights come with new, equal arrays)."""
    return a is b or (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
                      and np.array_equal(a, b))


def current(ident: Identity, src) -> Identity:
    """``ident`` with the source terms' coefficients read from ``src`` (same arrays, new numbers)."""
    c1 = ident.c1.copy()
    c1[ident.source_rows] = src.coef[ident.source_rc]
    return Identity(**{**ident.__dict__, "c1": c1})


# ---------------------------------------------------------------------- evaluation at a point
def entry_vector(ident: Identity, at) -> np.ndarray:
    """The svec-ordered matrix entries Q_ij (i <= j) of every block of ``ident`` at the point."""
    parts = []
    for psd, size, _, _ in ident.blocks:
        i, j = svec_pairs(size)
        parts.append(svec_to_matrix(at(psd.ids), size)[i, j])
    return np.concatenate(parts) if parts else np.zeros(0)


def term_values(ident: Identity, y_of, entries) -> np.ndarray:
    """The value of every term: c1 c2 factor (module docstring of :class:`Identity`)."""
    v = ident.c1 * ident.c2
    lin = ident.kind == 1
    v[lin] = v[lin] * y_of(ident.where[lin])
    gram = ident.kind == 2
    v[gram] = v[gram] * entries[ident.where[gram]]
    return v


def residual(ident: Identity, values, source_error=None) -> tuple[np.ndarray, np.ndarray]:
    """(fl(e), B) with |e_a| <= B_a for the exact e of these term values' factors."""
    e = np.bincount(ident.mon, weights=values, minlength=ident.n_mon)
    mag = np.bincount(ident.mon, weights=np.abs(values), minlength=ident.n_mon)
    bound = np.abs(e) + gam(2 * ident.count + 8) * mag
    if source_error is not None:
        bound = bound + source_error * (1 + 4 * EPS)
    return e, bound


def exact_residual(ident: Identity, a: int, y_of, entries, exact=None) -> Fraction:
    """e_a in rational arithmetic (each term's factors are floats, so exact; a decision in
    ``exact`` takes its rational value there)."""
    out = Fraction(0)
    for t in np.flatnonzero(ident.mon == a):
        d = int(ident.where[t])
        if ident.kind[t] == 1 and exact and d in exact:
            f = exact[d]
        else:
            f = Fraction(1) if ident.kind[t] == 0 else Fraction(float(
                y_of(ident.where[t:t + 1])[0] if ident.kind[t] == 1 else entries[ident.where[t]]))
        out += Fraction(float(ident.c1[t])) * Fraction(float(ident.c2[t])) * f
    return out


def unreachable_rows(ident: Identity, y_of, entries, fixed: dict):
    """The coefficient equations of the monomials no Gram product of any block gives but a free
    decision reaches: (constant, {decision: coefficient}) in rational arithmetic -- these must
    vanish exactly -- with the decisions in ``fixed`` (already corrected: their rational values)
    counted in the constant; and the decisions' current values."""
    reachable = np.zeros(ident.n_mon, dtype=bool)
    for mon in ident.pair_mon:
        reachable[mon] = True
    free = np.zeros(ident.n_mon, dtype=bool)
    free[ident.mon[ident.kind == 1]] = True
    rows, start = [], {}
    for a in np.flatnonzero(~reachable & free):
        c, lin = Fraction(0), {}
        for t in np.flatnonzero(ident.mon == a):
            w = Fraction(float(ident.c1[t])) * Fraction(float(ident.c2[t]))
            d = int(ident.where[t])
            if ident.kind[t] == 1 and d not in fixed:
                lin[d] = lin.get(d, 0) + w
                start[d] = Fraction(float(y_of(ident.where[t:t + 1])[0]))
            elif ident.kind[t] == 1:
                c += w * fixed[d]
            else:
                c += w * (1 if ident.kind[t] == 0 else Fraction(float(entries[d])))
        rows.append((c, lin))
    return rows, start


# ---------------------------------------------------------------------- faces
def forced_zero_rows(ident: Identity, k: int, kept: list) -> np.ndarray:
    """Rows of Gram block k that every exact certificate sets to zero, given the kept rows of
    all blocks: z_j^2 is produced by no other kept product of any block and no other term of (*)
    lands on it (its coefficient there is 0 whatever the decisions), so Q_jj = 0 and, Q being
    PSD, the whole row; iterated by the caller."""
    psd_size = ident.blocks[k][1]
    i, j = svec_pairs(psd_size)
    mon = ident.pair_mon[k]
    producers = np.zeros(ident.n_mon, dtype=np.int64)
    for b, mask in enumerate(kept):
        bi, bj = svec_pairs(ident.blocks[b][1])
        on = mask[bi] & mask[bj]
        np.add.at(producers, ident.pair_mon[b][on], 1)
    diag = np.flatnonzero(i == j)
    square = mon[diag]
    alone = (producers[square] == 1) & (ident.other_terms[square] == 0) & kept[k][i[diag]]
    return i[diag][alone]


def faces(ident: Identity, Qs, zeros) -> list:
    """Kept-row masks of the Gram blocks, one list per face tried, each a sound restriction (a
    certificate on a face is a certificate): the rows every exact certificate sets to zero
    removed (:func:`forced_zero_rows`, iterated); then also the rows whose square z_j^2 no other
    term of (*) lands on (its coefficient in the polynomial is 0); then the rows whose diagonal
    is below rel x the block's largest, rel in FACES. The constant monomial is always kept."""
    kept = [np.ones(Q.shape[0], dtype=bool) for Q in Qs]
    changed = True
    while changed:
        changed = False
        for k in range(len(Qs)):
            rows = forced_zero_rows(ident, k, kept)
            if rows.size:
                kept[k][rows] = False
                changed = True
    zero_square = []
    for k, Q in enumerate(Qs):
        i, j = svec_pairs(Q.shape[0])
        square = ident.pair_mon[k][i == j]
        zero_square.append(kept[k] & (ident.other_terms[square] > 0))
    out = [kept, zero_square] + [[m & (np.diag(Q) > rel * float(np.diag(Q).max(initial=0.0)))
                                  for m, Q in zip(kept, Qs)] for rel in FACES]
    unique = []
    for face in out:
        for m, z in zip(face, zeros):
            m[z] = True
        if not any(all(np.array_equal(a, b) for a, b in zip(face, seen)) for seen in unique):
            unique.append(face)
    return unique


def block_matrix(entries, off, size) -> np.ndarray:
    i, j = svec_pairs(size)
    Q = np.zeros((size, size))
    Q[i, j] = entries[off:off + i.size]
    Q[j, i] = entries[off:off + i.size]
    return Q

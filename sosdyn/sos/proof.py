"""Proofs at a point: every constraint of a program shown to hold at given decision values.

Floating point with proven rounding bounds, never a tolerance relative to a coefficient.
For an SOS constraint "source >= 0 on K" with Gram blocks Q_k (the main one and the clique
blocks of a sparse constraint), SOS multipliers sigma_i = z_i^T S_i z_i of g_i >= 0 and free
multipliers lambda_j of h_j = 0, every term of the identity

    e = source - sum_i sigma_i g_i - sum_j lambda_j h_j - sum_k z_k^T Q_k z_k        (*)

is a product of at most three floats, so each coefficient e_a is computed with
|fl(e_a) - e_a| <= gamma_(2 m_a + 6) sum |terms| (m_a terms; gamma_k = k u / (1 - k u), u the unit
roundoff; Higham, *Accuracy and stability of numerical algorithms*, ch. 3). At the point:

1. a multiplier block's rows of tiny diagonal are set to zero, and with lambda_min(S_i) < 0 it is
   raised to S_i + mu_i I on the rest (both changes join e); it must then be PSD (:func:`eig_lower`);
2. the Gram rows off a *face* are set to zero (:func:`faces`: rows the polynomial forces to zero --
   a square z_j^2 no other kept product gives, with no other term of (*) on it -- iterated; then
   rows whose diagonal is tiny, which is a restriction and always sound), their terms joining e;
3. e is absorbed: Q~_k = Q_k + E_k, E_k,ij = e_a / N_a over the N_a ordered kept pairs of the
   first block producing x^a (the smallest such E in Frobenius norm);
4. e is computed again at Q~ with its bound B_a >= |e~_a|: now the identity is
   source - sum sigma_i g_i - sum lambda_j h_j = sum_k z_k^T (Q~_k + E~_k) z_k + e~_rest exactly,
   ||E~_k||_2 <= ||E~_k||_F <= tau_k = (sum_{a owned by k} B_a^2 / N_a)^(1/2), and e~_rest (monomials
   no kept product gives) must vanish exactly (checked in rational arithmetic);
5. the constraint is proven when lambda_min(Q~_k) >= tau_k for every block, lambda_min bounded by
   :func:`eig_lower` (a Cholesky factor of Q~ - tI and its rounding bound);
6. on a set that bounds a box |x_i| <= R_i (:func:`~.sets.variable_bounds` of the multipliers'
   constraints), a residual on monomials no kept product gives is bounded there by
   c = sum_a B_a R^a and the constant row carries it: lambda_min(Q~ - c e_0 e_0^T) >= tau gives
   z^T (Q~ + E~) z >= c >= -e~_rest(x) on K (the old posterior's compact-set bound).

A constraint whose source polynomial is itself a rounding of an exact one (a change of variables,
:func:`~.sets.substituted`) carries ``source_error()``: the bound of each coefficient's rounding,
added to B_a, so the proof holds for the exact polynomial.

Then source = SOS + sum sigma_i g_i + sum lambda_j h_j >= 0 on K, whatever the size of the
coefficients. Blocks that belong to no constraint (new_sos, new_psd) must have
:func:`eig_lower` >= 0; ``add_ge`` rows must hold after their rounding bound; ``add_eq`` rows to
within the rounding of their own terms (4 gamma_(n+2) sum |terms|: no float vector meets most
equality rows exactly); cvxpy constraints are checked numerically (violation <= 1e-9 of their
scale), not proven. :func:`prove_program` applies all of this to a program at a point.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from ..poly import keys_to_exps, multiset_keys, unique_rows
from .conic import cvxpy_block_vars, positions
from .constraints import Basis, PsdBlock
from .sets import BasicSet, variable_bounds
from .gram import (SQRT2, EXACT_LDL_MAX, absorb_residual, exact_sub, gram_form, matrix_to_svec, proven_min_eig,
                   svec_pairs, svec_to_matrix)

EPS = np.finfo(float).eps
UNIT = EPS / 2
FACES = (1e-9, 1e-7, 1e-5)   # relative Gram diagonals below which a row leaves the face (heuristic faces)
CVXPY_TOL = 1e-9
MULTIPLIER_FACE = 1e-9   # a multiplier row whose diagonal is below this x the largest is set to zero


def gam(k):
    """gamma_k = k u / (1 - k u): the relative error bound of k floating-point operations."""
    ku = np.asarray(k, dtype=float) * UNIT
    return ku / (1.0 - ku)


def down(v: float) -> float:
    """A float at most v (two steps towards -inf: v may itself be a rounded sum)."""
    return math.nextafter(math.nextafter(float(v), -math.inf), -math.inf)


def eig_lower(A: np.ndarray) -> float:
    """A proven lower bound on lambda_min(A) for a symmetric float matrix A (-inf if none).

    With t below the estimated lambda_min and L = chol(fl(A - tI)), A - tI = L L^T + R exactly,
    |R| <= |fl(A - tI - L L^T)| (1 + 2u) + gamma_(2n+4) |L||L|^T + u |diag(A - tI)| entrywise
    (the rounding of forming A - tI, of L L^T and of the subtraction), so lambda_min(A) >= t -
    ||R||_F, the norm itself rounded up."""
    n = A.shape[0]
    if n == 0:
        return math.inf
    if not np.isfinite(A).all():
        return -math.inf
    norm = float(np.linalg.norm(A))
    if norm == 0.0:
        return 0.0
    lam = float(np.linalg.eigvalsh(A)[0])
    slack = (n + 4) * EPS * norm
    diag = np.arange(n)
    for k in range(6):
        t = lam - slack * 8.0**k
        B = A.copy()
        B[diag, diag] -= t
        try:
            L = np.linalg.cholesky(B)
        except np.linalg.LinAlgError:
            continue
        aL = np.abs(L)
        err = np.abs(B - L @ L.T) * (1 + 2 * UNIT) + gam(2 * n + 4) * (aL @ aL.T)
        err[diag, diag] += UNIT * np.abs(np.diag(B))
        r = float(np.linalg.norm(err)) * (1 + float(gam(n * n + 4)))
        if np.isfinite(r):
            return down(t - r)
    return -math.inf


# ---------------------------------------------------------------------- the identity's structure
def _cols(vars, sub) -> np.ndarray:
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
        k = _keys(basis.exps[i] + basis.exps[j], _cols(vars, basis.vars), width)
        add(k, np.where(i == j, -1.0, -2.0), np.ones(i.size), 2, offset + np.arange(i.size))
        pair_mon_keys.append(k)
        blocks.append((psd, psd.size, offset, True))
        offset += i.size
    n_gram_terms = sum(len(k) for k in keys)
    for m in mults:
        i, j = svec_pairs(m.psd.size)
        g = m.constraint.with_vars(vars)
        B = np.zeros((len(m.basis), len(vars)), dtype=np.int64)
        B[:, _cols(vars, m.basis.vars)] = m.basis.exps
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
    if hit is not None and hit[0] is con and len(hit[1]) == len(parts) and all(a is b for a, b in zip(hit[1], parts)) \
            and hit[2].source_mask.shape == src.coef.shape and not ((src.coef != 0) & ~hit[2].source_mask).any():
        _IDENTITIES.move_to_end(key)
        return current(hit[2], src)
    out = build_identity(con)
    _IDENTITIES[key] = (con, parts, out)
    if len(_IDENTITIES) > _KEPT:
        _IDENTITIES.popitem(last=False)
    return out


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
    bound = np.abs(e) + gam(2 * ident.count + 6) * mag
    if source_error is not None:
        bound = bound + source_error * (1 + 4 * EPS)
    return e, bound


def exact_residual(ident: Identity, a: int, y_of, entries) -> Fraction:
    """e_a in rational arithmetic (each term's factors are floats, so exact)."""
    out = Fraction(0)
    for t in np.flatnonzero(ident.mon == a):
        f = Fraction(1) if ident.kind[t] == 0 else Fraction(float(
            y_of(ident.where[t:t + 1])[0] if ident.kind[t] == 1 else entries[ident.where[t]]))
        out += Fraction(float(ident.c1[t])) * Fraction(float(ident.c2[t])) * f
    return out


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


# ---------------------------------------------------------------------- one constraint
def constant_need(A, k0: int, tau: float) -> float:
    """The signed number c with lambda_min(A + d e_k0 e_k0^T) >= tau iff d >= c (up to rounding),
    or inf when no d works. With A' = A without row/column k0 and b = A[others, k0]: PSD iff
    A' - tau I > 0 and a_00 + d - tau >= b^T (A' - tau I)^{-1} b (Schur complement)."""
    rest = np.delete(np.arange(A.shape[0]), k0)
    Ar = A[np.ix_(rest, rest)] - tau * np.eye(rest.size)
    if rest.size and np.linalg.eigvalsh(Ar)[0] <= 8 * (rest.size + 4) * EPS * float(np.linalg.norm(A)):
        return math.inf
    b = A[rest, k0]
    return tau - A[k0, k0] + (float(b @ np.linalg.solve(Ar, b)) if rest.size else 0.0)


@dataclass
class ConstraintProof:
    """The outcome of :func:`prove_constraint`: ``ok``, and per Gram block the absorbed kept
    matrix ``A[k]`` (Q~ on the face), its proven smallest eigenvalue ``lam[k]``, the bound
    ``tau[k]`` it must reach, the face ``kept[k]``, the kept row of the constant monomial
    ``zero[k]`` (-1: none) and the raise of that entry the block needs, ``need[k]`` (negative:
    room to give; :func:`constant_need`); ``owner``/``N`` say which block absorbs each monomial
    over how many ordered pairs; ``reason`` when not ok."""

    ok: bool
    A: list = field(default_factory=list)
    lam: list = field(default_factory=list)
    tau: list = field(default_factory=list)
    kept: list = field(default_factory=list)
    zero: list = field(default_factory=list)
    need: list = field(default_factory=list)
    owner: np.ndarray | None = None
    N: np.ndarray | None = None
    ident: Identity | None = None
    reason: str = ""
    entries: np.ndarray | None = None    # the proven certificate: Q~ on the face, raised multipliers

    @property
    def margin(self) -> float:
        return min((a - t for a, t in zip(self.lam, self.tau)), default=math.inf)


def _raise_multipliers(ident: Identity, entries: np.ndarray) -> str:
    """Put every multiplier block on its face and raise it there (in ``entries``, step 1): rows
    whose diagonal is below MULTIPLIER_FACE x the largest are set to zero (their terms join the
    residual), the rest raised to S + mu I with eig_lower >= 0 -- mu on a near-zero row would be
    multiplied by every coefficient of its constraint. A reason if a block cannot be raised."""
    for psd, size, off, gram in ident.blocks:
        if gram or not size:
            continue
        i, j = svec_pairs(size)
        S = _matrix(entries, off, size)
        d = np.diag(S)
        keep = d > MULTIPLIER_FACE * float(np.abs(d).max(initial=0.0))
        entries[off:off + i.size][~(keep[i] & keep[j])] = 0.0
        S = _matrix(entries, off, size)[np.ix_(keep, keep)]
        lam = eig_lower(S)
        mu = 0.0
        for _ in range(8):
            if lam >= 0:
                break
            if not np.isfinite(lam):
                return f"multiplier {psd.name!r} is not finite"
            mu = mu + (-lam) * (1 + 1e-6) + 4 * EPS * float(np.abs(S).max())
            lam = eig_lower(S + mu * np.eye(S.shape[0]))
        if lam < 0:
            return f"multiplier {psd.name!r} cannot be made PSD"
        entries[off:off + i.size] += np.where((i == j) & keep[i], mu, 0.0)
    return ""


def _matrix(entries, off, size) -> np.ndarray:
    i, j = svec_pairs(size)
    Q = np.zeros((size, size))
    Q[i, j] = entries[off:off + i.size]
    Q[j, i] = entries[off:off + i.size]
    return Q


def prove_constraint(con, at, prefer=None) -> ConstraintProof:
    """Prove ``con`` at the point (``at(ids)``: the values of decision ids), trying each face of
    :func:`faces` (after ``prefer``, a list of kept masks of its Gram blocks, when given); the
    first proof wins, else the attempt with the largest margin is returned (its numbers guide the
    corrections of :mod:`.posterior`)."""
    ident = identity_of(con)
    err = getattr(con, "source_error", None)            # |rounding| of each source coefficient (rows x 1 + ids)
    src_err = None
    if err is not None:
        E = err()
        rs, cs = ident.source_rc
        ids = con.source.with_vars(con.basis.vars).ids
        w = E[rs, cs] * np.where(cs == 0, 1.0, np.abs(at(ids[np.maximum(cs - 1, 0)])) if ids.size else 1.0)
        src_err = np.bincount(ident.mon[ident.source_rows], weights=w, minlength=ident.n_mon)
    base = entry_vector(ident, at)
    why = _raise_multipliers(ident, base)
    if why:
        return ConstraintProof(False, reason=f"constraint {con.name!r}: {why}")
    grams = [(size, off) for _, size, off, g in ident.blocks if g]
    Qs = [_matrix(base, off, size) for size, off in grams]
    zeros = [np.flatnonzero(~basis.exps.any(axis=1))[:1] for basis, _ in con.gram_blocks]
    best = None
    for kept in ([prefer] if prefer is not None else []) + faces(ident, Qs, zeros):
        proof = _prove_on_face(con.name, ident, base, grams, kept, zeros, at, src_err)
        if proof.ok:
            return proof
        if best is None or (proof.lam and (not best.lam or proof.margin > best.margin)):
            best = proof
    return best


def _bound_of(ident, entries, at, src_err, owner, N, n_blocks):
    """(fl e, B, tau per block) at these entries (module docstring, step 4)."""
    e, bound = residual(ident, term_values(ident, at, entries), src_err)
    own = owner >= 0
    tau2 = np.bincount(owner[own], weights=bound[own] ** 2 / N[own], minlength=n_blocks)
    return e, bound, np.sqrt(tau2) * (1 + float(gam(ident.n_mon + 8)))


def _prove_on_face(name, ident, base, grams, kept, zeros, at, src_err) -> ConstraintProof:
    entries = base.copy()
    owner = np.full(ident.n_mon, -1, dtype=np.int64)
    N = np.zeros(ident.n_mon)
    on_pairs = []
    for k, (size, off) in enumerate(grams):
        i, j = svec_pairs(size)
        on = kept[k][i] & kept[k][j]
        entries[off:off + i.size][~on] = 0.0
        on_pairs.append(on)
    for k in reversed(range(len(grams))):              # the first block producing a owns it
        i, j = svec_pairs(grams[k][0])
        mon = ident.pair_mon[k][on_pairs[k]]
        Nk = np.bincount(mon, weights=np.where(i == j, 1.0, 2.0)[on_pairs[k]], minlength=ident.n_mon)
        has = Nk > 0
        owner[has], N[has] = k, Nk[has]
    e, _ = residual(ident, term_values(ident, at, entries))
    for k, (size, off) in enumerate(grams):            # absorb: Q~ = Q + E on the face
        mon = ident.pair_mon[k]
        own = on_pairs[k] & (owner[mon] == k)
        entries[off:off + mon.size][own] += e[mon[own]] / N[mon[own]]
    zero = [int(np.cumsum(kept[k])[z[0]] - 1) if z.size and kept[k][z[0]] else -1 for k, z in enumerate(zeros)]
    e, bound, tau = _bound_of(ident, entries, at, src_err, owner, N, len(grams))
    need = _needs(entries, grams, kept, zero, tau)
    shared = [k for k in range(len(grams)) if zero[k] >= 0]
    if len(shared) > 1 and any(n > 0 for n in need) and sum(need[k] for k in shared) <= 0:
        spare = -sum(need[k] for k in shared) / len(shared)     # move constant to the blocks short of it
        for k in shared:
            size, off = grams[k]
            z = int(np.flatnonzero(kept[k])[zero[k]])
            entries[off + z * (z + 1) // 2 + z] += need[k] + spare
        e, bound, tau = _bound_of(ident, entries, at, src_err, owner, N, len(grams))
        need = _needs(entries, grams, kept, zero, tau)
    gap = 0.0                                           # step 6 of the module docstring
    for a in np.flatnonzero((owner < 0) & (bound > 0)):
        if exact_residual(ident, int(a), at, entries) != 0:
            if ident.radius is None or not shared:
                return ConstraintProof(False, reason=(
                    f"constraint {name!r}: a residual {e[a]:.2e} on a monomial that no kept Gram "
                    "product gives (it cannot be absorbed, and the set bounds no box)"))
            exps = keys_to_exps(ident.keys[a:a + 1], ident.radius.size)[0]
            gap += float(bound[a]) * float(np.prod(ident.radius ** exps))
    A = [_matrix(entries, off, size)[np.ix_(kept[k], kept[k])] for k, (size, off) in enumerate(grams)]
    if gap:
        k0 = shared[0]
        cut = gap * (1 + 1e-12) + 4 * EPS * abs(A[k0][zero[k0], zero[k0]])
        A[k0][zero[k0], zero[k0]] -= cut
        need[k0] += cut
    lam = [eig_lower(Q) for Q in A]
    ok = all(lk >= tk for lk, tk in zip(lam, tau))
    worst = int(np.argmin([lk - tk for lk, tk in zip(lam, tau)])) if grams else 0
    reason = "" if ok else (f"constraint {name!r}: Gram block {worst} has proven smallest eigenvalue "
                            f"{lam[worst]:.3e}, below the residual it must absorb ({tau[worst]:.2e})")
    return ConstraintProof(ok, A, lam, [float(t) for t in tau], kept, zero, need, owner, N, ident, reason, entries)


def _needs(entries, grams, kept, zero, tau) -> list:
    """Per block, the raise of its constant entry it needs (:func:`constant_need`; inf: no raise
    helps, nan: no constant row), with a little room for the rounding of the raise itself."""
    out = []
    for k, (size, off) in enumerate(grams):
        if zero[k] < 0:
            out.append(math.nan)
            continue
        A = _matrix(entries, off, size)[np.ix_(kept[k], kept[k])]
        slack = 16 * (A.shape[0] + 4) * EPS * float(np.linalg.norm(A))
        out.append(constant_need(A, zero[k], float(tau[k]) * (1 + 1e-9) + slack))
    return out


# ---------------------------------------------------------------------- the whole program
@dataclass
class PointProof:
    """:func:`prove_program`'s outcome: ``ok``; the proof of every SOS constraint (by name) and
    the reasons of what failed."""

    ok: bool
    constraints: dict
    reasons: list

    def summary(self) -> str:
        return "; ".join(self.reasons) if self.reasons else "every constraint proven"


def linear_row_ok(rows, y_of) -> tuple[bool, str]:
    """An ``add_ge`` row holds after its rounding bound, an ``add_eq`` row to within the rounding
    of its own terms (module docstring)."""
    n = rows.rhs.size
    terms = rows.vals * y_of(rows.ids)
    lhs = np.bincount(rows.rows, weights=terms, minlength=n) - rows.rhs
    mag = np.bincount(rows.rows, weights=np.abs(terms), minlength=n) + np.abs(rows.rhs)
    cnt = np.bincount(rows.rows, minlength=n) + 2
    tol = gam(2 * cnt + 4) * mag
    bad = np.flatnonzero(lhs - tol < 0) if rows.kind == "ge" else np.flatnonzero(np.abs(lhs) > 4 * tol)
    if bad.size:
        r = int(bad[0])
        return False, (f"{'inequality' if rows.kind == 'ge' else 'equality'} {rows.name!r} row {r}: "
                       f"{lhs[r]:.3e} (rounding bound {tol[r]:.1e})")
    return True, ""


def cvxpy_ok(program, ids, x) -> tuple[bool, str]:
    """The program's cvxpy constraints at x, numerically (module docstring)."""
    if not program.cvxpy_constraints:
        return True, ""
    for b, var in zip(program.blocks, cvxpy_block_vars(program)):
        var.value = x[positions(ids, b.ids)]
    for k, c in enumerate(program.cvxpy_constraints):
        viol = float(np.max(c.violation()))
        scale = max([1.0] + [float(np.abs(a.value).max()) for a in c.args if a.value is not None])
        if not viol <= CVXPY_TOL * scale:
            return False, f"cvxpy constraint {k} violated by {viol:.2e}"
    return True, ""


def prove_program(program, ids, x, prefer=None) -> PointProof:
    """Prove every constraint of ``program`` at the decision values x (ordered as ``ids``);
    ``prefer`` maps a constraint's name to kept masks of its Gram blocks, tried first."""
    if not np.isfinite(x).all():
        return PointProof(False, {}, ["the point has non-finite entries"])
    at = lambda block_ids: x[positions(ids, np.asarray(block_ids, dtype=np.int64))]  # noqa: E731
    proofs, reasons, owned = {}, [], set()
    for con in program.sos_constraints:
        proof = prove_constraint(con, at, (prefer or {}).get(con.name))
        proofs[con.name] = proof
        if not proof.ok:
            reasons.append(proof.reason)
        owned.update(id(psd) for _, psd in con.gram_blocks)
        owned.update(id(m.psd) for m in con.multipliers)
    for b in program.blocks:
        if b.psd is not None and id(b.psd) not in owned and b.psd.size:
            lam = eig_lower(svec_to_matrix(at(b.ids), b.psd.size))
            if not lam >= 0:
                reasons.append(f"{b.psd.role} block {b.name!r}: proven smallest eigenvalue {lam:.3e} < 0")
    for rows in program.linear:
        if rows.role == "user":
            ok, why = linear_row_ok(rows, at)
            if not ok:
                reasons.append(why)
    ok, why = cvxpy_ok(program, ids, x)
    if not ok:
        reasons.append(why)
    return PointProof(not reasons, proofs, reasons)


def certificate_point(program, ids, x, judged: PointProof) -> np.ndarray:
    """x with every constraint's Gram and multiplier blocks replaced by the certificate the judge
    proved (Q~ on its face, the raised multipliers): the numbers a proven Solution hands out."""
    y = x.copy()
    for con in program.sos_constraints:
        proof = judged.constraints.get(con.name)
        if proof is None or proof.entries is None:
            continue
        for psd, size, off, _ in proof.ident.blocks:
            i, j = svec_pairs(size)
            y[positions(ids, psd.ids)] = np.where(i == j, 1.0, SQRT2) * proof.entries[off:off + i.size]
    return y


# ---------------------------------------------------------------------- a given certificate
class _Given:
    """"p = z^T Q z" for a numeric p, basis exponents and Q, shaped as a constraint for the judge."""

    def __init__(self, p, basis_exps, size):
        self.name, self.source = "given", p
        self.basis = Basis(p.vars, np.asarray(basis_exps, dtype=np.int64))
        self.psd = PsdBlock("given", np.arange(size * (size + 1) // 2, dtype=np.int64), size)
        self.gram_blocks, self.multipliers, self.eq_multipliers = [(self.basis, self.psd)], [], []


def prove_gram(p, basis_exps, Q) -> tuple[bool, str]:
    """(proven, why not) for the certificate p = z^T Q z, Q >= 0 of a numeric polynomial: by the
    judge (module docstring, on its faces), else in rational arithmetic -- the exact residual
    absorbed by the orthogonal projection and the result proven PSD (:func:`~.gram.proven_min_eig`,
    an exact LDL^T for a singular one)."""
    Q = np.asarray(Q, dtype=float)
    if not np.isfinite(Q).all():
        return False, "the Gram matrix is not finite"
    con = _Given(p, basis_exps, Q.shape[0])
    s = matrix_to_svec(Q)
    proof = prove_constraint(con, lambda ids: s[ids])
    if proof.ok:
        return True, ""
    if Q.shape[0] <= EXACT_LDL_MAX:
        Qx = np.array([[Fraction(float(v)) for v in row] for row in Q], dtype=object)
        residual = exact_sub({tuple(int(a) for a in e): Fraction(float(c)) for e, c in zip(p.exps, p.coef[:, 0]) if c},
                             gram_form(con.basis.exps, Qx))
        absorbed, _ = absorb_residual(con.basis.exps, Qx, residual)
        if absorbed is not None and proven_min_eig(absorbed) is not None:
            return True, ""
    return False, proof.reason

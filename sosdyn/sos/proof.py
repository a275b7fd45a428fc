"""Proofs at a point: every constraint of a program shown to hold at given decision values.

Floating point with proven rounding bounds, never a tolerance relative to a coefficient.
For an SOS constraint "source >= 0 on K" with Gram blocks Q_k (the main one and the clique
blocks of a sparse constraint), SOS multipliers sigma_i = z_i^T S_i z_i of g_i >= 0 and free
multipliers lambda_j of h_j = 0, every term of the identity

    e = source - sum_i sigma_i g_i - sum_j lambda_j h_j - sum_k z_k^T Q_k z_k        (*)

is a product of at most three floats, so each coefficient e_a is computed with
|fl(e_a) - e_a| <= gamma_(2 m_a + 8) sum |terms| (m_a terms; gamma_k = k u / (1 - k u), u the unit
roundoff; Higham, *Accuracy and stability of numerical algorithms*, ch. 3). At the point:

0. the coefficients of monomials no Gram product gives (a free multiplier's top terms) must vanish
   exactly: the free decisions they involve are corrected in rational arithmetic (their floats
   are the nearest, one more rounding in the bound), so the point proven is rational there;
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
   :func:`~.eigen.eig_lower` (a Cholesky factor of Q~ - tI and its rounding bound) -- or, failing
   that, the same in balanced coordinates: lambda_min(D Q~_k D) against ||D E~_k D||_F, D a
   diagonal of powers of two (:mod:`.eigen`; exact, and far smaller where the monomials' sizes
   differ by orders of magnitude at the minimiser);
6. a residual on a monomial x^a no kept product gives is dominated by the squares of the basis:
   with a = sum_j lam_j 2 b_j (lam >= 0, sum 1, exact rationals from an LP vertex) the weighted
   AM-GM inequality gives |x^a| <= sum_j lam_j z_j^2, so B_a lam_j comes off the diagonal entries
   (:func:`dominated`); else, on a set that bounds a box |x_i| <= R_i (:func:`~.sets.variable_bounds`
   of the multipliers' constraints), |e_a x^a| <= B_a R^a there and the constant row carries it:
   lambda_min(Q~ - c e_0 e_0^T) >= tau, c = sum B_a R^a, gives z^T (Q~ + E~) z >= c on K.

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
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
from scipy.optimize import linprog

from ..poly import keys_to_exps
from .conic import cvxpy_block_vars, positions
from .constraints import Basis, PsdBlock
from .gram import (EXACT_LDL_MAX, SQRT2, absorb_residual, exact_solution, exact_sub, gram_form, matrix_to_svec,
                   proven_min_eig, svec_pairs, svec_to_matrix)
from .eigen import balanced_blocks, better_guide, constant_need, eig_lower
from .identity import (EPS, Identity, block_matrix, entry_vector, exps_over, exact_residual, faces, gam,
                       identity_of, residual, term_values, unreachable_rows)

CVXPY_TOL = 1e-9
MULTIPLIER_FACE = 1e-9   # a multiplier row whose diagonal is below this x the largest is set to zero


# ---------------------------------------------------------------------- one constraint
@dataclass
class ConstraintProof:
    """The outcome of :func:`prove_constraint`: ``ok``, and per Gram block the absorbed kept
    matrix ``A[k]`` (Q~ on the face), its proven smallest eigenvalue ``lam[k]``, the bound
    ``tau[k]`` it must reach, the face ``kept[k]``, the kept row of the constant monomial
    ``zero[k]`` (-1: none) and the raise of that entry the block needs, ``need[k]`` (negative:
    room to give; :func:`constant_need`); ``owner``/``N`` say which block absorbs each monomial
    over how many ordered pairs; ``reason`` when not ok. ``shift[k]``: when the blocks are judged
    in balanced coordinates (:mod:`.eigen`), log2 of D's diagonal on the kept rows, and A, lam, tau
    and need are those of D A D (None: as they are)."""

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
    shift: list | None = None
    margin: float = math.inf             # min(lam - tau) as first judged (the choice among failing faces)


def _raise_multipliers(ident: Identity, entries: np.ndarray) -> str:
    """Put every multiplier block on its face and raise it there (in ``entries``, step 1): rows
    whose diagonal is below MULTIPLIER_FACE x the largest are set to zero (their terms join the
    residual), the rest raised to S + mu I with eig_lower >= 0 -- mu on a near-zero row would be
    multiplied by every coefficient of its constraint. A reason if a block cannot be raised."""
    for psd, size, off, gram in ident.blocks:
        if gram or not size:
            continue
        i, j = svec_pairs(size)
        S = block_matrix(entries, off, size)
        d = np.diag(S)
        keep = d > MULTIPLIER_FACE * float(np.abs(d).max(initial=0.0))
        entries[off:off + i.size][~(keep[i] & keep[j])] = 0.0
        S = block_matrix(entries, off, size)[np.ix_(keep, keep)]
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


def settle_decisions(ident, at, entries, exact: dict, place) -> str:
    """Correct the free decisions in rational arithmetic so that the coefficients of the monomials no
    Gram product gives vanish exactly (step 0 of the module docstring; ``exact`` collects the
    rational values, ``place(d, value)`` writes their floats into the point); a reason if they
    cannot."""
    rows, start = unreachable_rows(ident, at, entries, exact)
    rows = [(c, lin) for c, lin in rows if c or lin]
    if not rows:
        return ""
    if any(not lin and c for c, lin in rows):
        return "a monomial no Gram product gives has a fixed non-zero coefficient"
    change = exact_solution(rows, start)
    if change is None:
        return "the coefficients of the monomials no Gram product gives cannot all vanish"
    for d, v in change.items():
        exact[d] = start[d] + v
        place(d, exact[d])
    return ""


def prove_constraint(con, at, prefer=None, exact=None, place=None) -> ConstraintProof:
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
    if not why and exact is not None:
        why = settle_decisions(ident, at, base, exact, place)
    if why:
        return ConstraintProof(False, reason=f"constraint {con.name!r}: {why}")
    grams = [(size, off) for _, size, off, g in ident.blocks if g]
    Qs = [block_matrix(base, off, size) for size, off in grams]
    zeros = [np.flatnonzero(~basis.exps.any(axis=1))[:1] for basis, _ in con.gram_blocks]
    block_exps = [exps_over(basis, con.basis.vars) for basis, _ in con.gram_blocks]
    best = None
    for kept in ([prefer] if prefer is not None else []) + faces(ident, Qs, zeros):
        proof = _prove_on_face(con.name, ident, base, grams, kept, zeros, at, src_err, block_exps, exact)
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


def dominated(exps, block_exps, kept):
    """(block k, its kept rows j, weights lam_j >= 0 summing to 1) with sum_j lam_j 2 b_j = exps
    exactly (rational lam from an LP vertex, checked in exact arithmetic), so |x^a| <= sum_j lam_j
    z_j(x)^2 everywhere by the weighted AM-GM inequality; None if no block's kept squares have x^a in
    their convex hull."""
    for k, (B, mask) in enumerate(zip(block_exps, kept)):
        rows = np.flatnonzero(mask)
        if not rows.size:
            continue
        twice = 2 * B[rows]
        res = linprog(np.zeros(rows.size), A_eq=np.vstack([twice.T, np.ones(rows.size)]),
                      b_eq=np.append(exps, 1.0).astype(float), bounds=(0, None), method="highs")
        if res.status != 0:
            continue
        lam = [Fraction(float(v)).limit_denominator(10**6) for v in res.x]
        if sum(lam) == 1 and all(sum(lk * int(t[c]) for lk, t in zip(lam, twice)) == int(exps[c])
                                 for c in range(exps.size)) and min(lam) >= 0:
            on = [j for j, lk in enumerate(lam) if lk]
            return k, np.searchsorted(rows, rows[on]), np.array([math.nextafter(float(lam[j]), math.inf) for j in on])
    return None


def _prove_on_face(name, ident, base, grams, kept, zeros, at, src_err, block_exps, exact=None) -> ConstraintProof:
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
    A = [block_matrix(entries, off, size)[np.ix_(kept[k], kept[k])] for k, (size, off) in enumerate(grams)]
    gap, cuts = 0.0, False                              # step 6 of the module docstring
    for a in np.flatnonzero((owner < 0) & (bound > 0)):
        if exact_residual(ident, int(a), at, entries, exact) == 0:
            continue
        exps = keys_to_exps(ident.keys[a:a + 1], len(block_exps[0][0]) if block_exps[0].size else 0)[0]
        spread = dominated(exps, block_exps, kept)
        if spread is not None:                          # |x^a| <= sum_j lam_j z_j^2 (weighted AM-GM)
            k, rows, lam = spread
            A[k][rows, rows] -= float(bound[a]) * lam * (1 + 1e-12)
            cuts = True
        elif ident.radius is not None and shared:
            gap += float(bound[a]) * float(np.prod(ident.radius ** exps))
        else:
            return ConstraintProof(False, reason=(
                f"constraint {name!r}: a residual {e[a]:.2e} on a monomial that no kept Gram product "
                "gives and no convex combination of their squares dominates (and the set bounds no box)"))
    if gap:
        k0 = shared[0]
        A[k0][zero[k0], zero[k0]] -= gap * (1 + 1e-12) + 4 * EPS * abs(A[k0][zero[k0], zero[k0]])
    if gap or cuts:
        need = [math.nan if zero[k] < 0 else constant_need(
            A[k], zero[k], float(tau[k]) * (1 + 1e-9) + 16 * (A[k].shape[0] + 4) * EPS * float(np.linalg.norm(A[k])))
            for k in range(len(grams))]
    lam = [eig_lower(Q) for Q in A]
    ok = all(lk >= tk for lk, tk in zip(lam, tau))
    margin, shift = min((lk - tk for lk, tk in zip(lam, tau)), default=math.inf), None
    if not ok:                                          # the same certificate, in balanced coordinates:
        balanced = balanced_blocks(A, kept, block_exps, ident, grams, owner, N, bound, zero)
        if balanced is not None:
            ok_b = all(lk >= tk for lk, tk in zip(balanced[1], balanced[2]))
            if ok_b or better_guide(balanced[3], need):
                (A, lam, tau, need, shift), ok = balanced, ok_b
    worst = int(np.argmin([lk - tk for lk, tk in zip(lam, tau)])) if grams else 0
    reason = "" if ok else (f"constraint {name!r}: Gram block {worst} has proven smallest eigenvalue "
                            f"{lam[worst]:.3e}, below the residual it must absorb ({tau[worst]:.2e})")
    return ConstraintProof(ok, A, lam, [float(t) for t in tau], kept, zero, need, owner, N, ident, reason, entries,
                           shift, margin)


def _needs(entries, grams, kept, zero, tau) -> list:
    """Per block, the raise of its constant entry it needs (:func:`constant_need`; inf: no raise
    helps, nan: no constant row), with a little room for the rounding of the raise itself."""
    out = []
    for k, (size, off) in enumerate(grams):
        if zero[k] < 0:
            out.append(math.nan)
            continue
        A = block_matrix(entries, off, size)[np.ix_(kept[k], kept[k])]
        slack = 16 * (A.shape[0] + 4) * EPS * float(np.linalg.norm(A))
        out.append(constant_need(A, zero[k], float(tau[k]) * (1 + 1e-9) + slack))
    return out


# ---------------------------------------------------------------------- the whole program
@dataclass
class PointProof:
    """:func:`prove_program`'s outcome: ``ok``; the proof of every SOS constraint (by name), the
    reasons of what failed; the point proven (``x``; ``exact``: the decisions it holds as rationals)."""

    ok: bool
    constraints: dict
    reasons: list
    x: np.ndarray | None = None          # the point proven: x with the corrected decisions' floats
    exact: dict = field(default_factory=dict)   # decision id -> its rational value (step 0)

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
        return PointProof(False, {}, ["the point has non-finite entries"], x)
    x, exact = x.copy(), {}
    at = lambda block_ids: x[positions(ids, np.asarray(block_ids, dtype=np.int64))]  # noqa: E731

    def place(d, value):
        x[positions(ids, np.array([d], dtype=np.int64))] = float(value)
    proofs, reasons, owned = {}, [], set()
    for con in program.sos_constraints:
        proof = prove_constraint(con, at, (prefer or {}).get(con.name), exact, place)
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
    return PointProof(not reasons, proofs, reasons, x, exact)


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

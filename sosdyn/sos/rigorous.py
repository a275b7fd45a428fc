"""Rigorous bounds: an objective value proven by exact arithmetic on a numerical certificate.

A decision vector d' is found at which every certificate holds *exactly*, in rational
arithmetic on the floats (:func:`prove_point`, exact helpers in :mod:`.gram`):

1. facial reduction: Gram diagonals that vanish at the solver's point (below FACE_TOL
   relative) are fixed to exactly zero with their rows and columns;
2. rows no Gram matrix can absorb -- coefficients of monomials no kept z_i z_j produces
   (forced to zero by coefficient matching) and ``add_eq`` rows -- are made to hold by the
   minimum-norm exact (rational) correction of the decisions;
3. each constraint's polynomial is evaluated exactly (an ``add_nonneg_on`` one rebuilt from
   its source, multipliers and constraint polynomials), its residual absorbed into Q[K, K]
   (the exact orthogonal projection onto the matching Gram matrices), and every block proven
   positive semidefinite (``proven_min_eig``); ``add_ge`` rows must hold exactly.

The objective at d', computed exactly and rounded to the safe side, is the proven bound
(:func:`prove_bound`). The starting point comes from

* ``shift``: the solver's point with a single-decision objective moved towards its worse
  side (maximize g s.t. p - g SOS: g lowered until Q + E stays PSD; Loefberg 2009,
  "Pre- and post-processing sum-of-squares programs in practice"), multiplier blocks with
  slightly negative eigenvalues raised by a multiple of I; or
* ``tightened``: a re-solve of ``program.tightened(...)`` with every kept block tightened to
  Q[K, K] >= eps I (eps relative to the block's scale, from 1e-12 up), so the point has a
  margin the residual fits under.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from ..errors import UnverifiedSolutionError
from .conic import objective_value, positions
from .gram import (SQRT2, absorb_residual, evaluate_affine, exact, exact_affine, exact_correction,
                   exact_gram, exact_sub, float_down, gram_form, merge_affine, proven_min_eig,
                   svec_pairs, svec_to_matrix)
from .objective import QuadraticForm, affine_rows, is_cvxpy
from .eigen import eig_lower

ANSWERED = ("optimal", "optimal_inaccurate")    # solver statuses that carry an answer
FACE_TOL = 1e-7          # a Gram diagonal below this (relative) is taken as 0
TIGHTENINGS = (1e-12, 3e-12, 1e-11, 3e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6)  # Q >= eps I (relative)
QUICK_TIGHTENINGS = (1e-11, 3e-11, 1e-10, 1e-9)   # the automatic attempt of a plain solve (proven.full_proof)
SHIFT_MAX = 1e-7         # largest relative shift tried before tightening


@dataclass(frozen=True)
class Bound:
    """An objective value proven by exact arithmetic on a numerical certificate.

    ``sense`` "max": the program provably attains ``proven`` (for "maximize g s.t. p - g
    SOS", p >= proven everywhere), so proven <= the optimum; "min": proven >= the optimum;
    None: a feasibility program (``proven`` None, the certificate itself is exact).
    ``x`` is the rational decision vector at which every certificate holds exactly, rounded
    to floats (ordered as the solution's ``data.ids``); ``margins`` the proven lower bound on
    lambda_min of every Gram block there (0 for a block proven PSD but singular).
    """

    sense: str | None
    solver_value: float | None
    proven: float | None
    method: str
    x: np.ndarray = field(repr=False)
    margins: dict = field(repr=False)
    seconds: float = 0.0

    @property
    def gap(self) -> float:
        """|solver value - proven bound|: what the proof cost."""
        if self.proven is None:
            return 0.0
        return abs(self.solver_value - self.proven)

    def __str__(self) -> str:
        if self.sense is None:
            return f"feasibility certificate proven exactly ({self.method})"
        rel = ">=" if self.sense == "max" else "<="
        return (f"optimum {rel} {self.proven!r} proven (solver value {self.solver_value!r}, gap "
                f"{self.gap:.2e}, method {self.method}, {self.seconds * 1e3:.0f} ms)")


def _exps_in(basis, vars) -> np.ndarray:
    """A basis's exponent rows with columns in the order of ``vars`` (missing ones zero)."""
    out = np.zeros((len(basis), len(vars)), dtype=np.int64)
    for c, v in enumerate(basis.vars):
        out[:, vars.index(v)] = basis.exps[:, c]
    return out


def constraint_map(con) -> dict:
    """The polynomial of an SOS constraint as an exact affine map of the decisions.

    For ``add_nonneg_on`` it is rebuilt from the source, the multipliers sigma_i = z^T S z
    (S_ij = s_k SQRT2 / 2, :mod:`.gram`) and the constraint polynomials, so it is the
    statement itself and not its floating-point expansion.
    """
    vars = con.basis.vars
    out = exact_affine(con.source.with_vars(vars))
    for mult in con.multipliers:
        B = _exps_in(mult.basis, vars)
        g = mult.constraint.with_vars(vars)
        i, j = svec_pairs(len(mult.basis))
        weight = [Fraction(1) if a == b else exact(SQRT2) for a, b in zip(i, j)]
        for k, (a, b) in enumerate(zip(i, j)):
            part = {tuple(int(v) for v in B[a] + B[b] + g.exps[r]): [Fraction(0), {int(mult.psd.ids[k]): -weight[k] * exact(g.coef[r, 0])}]
                    for r in range(g.nterms)}
            merge_affine(out, part)
    for mult in con.eq_multipliers:
        h = mult.constraint.with_vars(vars)
        for r in range(h.nterms):
            merge_affine(out, exact_affine(mult.poly.with_vars(vars), -exact(h.coef[r, 0]), h.exps[r]))
    return out


def _svec_outside(size: int, K: np.ndarray) -> np.ndarray:
    """svec positions of the entries in a row or column outside the kept indices K."""
    i, j = svec_pairs(size)
    return np.flatnonzero(~(np.isin(i, K) & np.isin(j, K)))


def prove_point(program, ids: np.ndarray, x: np.ndarray, kept: dict | None = None):
    """Check every certificate of ``program`` exactly near values x of decision ``ids``.

    ``kept`` maps id(PsdBlock) to the indices K a block keeps (default all): its other rows
    and columns are set to exactly zero (facial reduction) and only Q[K, K] must be PSD.
    The point is then corrected exactly (``exact_correction``) so that the rows no Gram
    matrix can absorb hold: coefficients of monomials no z_i z_j (i, j in K) produces, and
    the linear equalities. Each remaining residual is absorbed into Q[K, K]
    (``absorb_residual``) and every block proven PSD (``proven_min_eig``).
    Returns (x', margins, None) -- the exact point and the proven lower bound on
    lambda_min of every block -- or (None, None, reason) naming the first block that fails.
    """
    kept = kept or {}
    xq = {int(d): exact(v) for d, v in zip(ids, x)}
    face = lambda psd: np.asarray(kept.get(id(psd), np.arange(psd.size)), dtype=np.int64)  # noqa: E731
    fixed = set()
    for b in program.blocks:
        if b.psd is not None:
            fixed.update(int(d) for d in b.ids[_svec_outside(b.psd.size, face(b.psd))])
    for d in fixed:
        xq[d] = Fraction(0)
    maps, rows = [], []
    for con in program.sos_constraints:
        amap = constraint_map(con)
        K = face(con.psd)
        B = con.basis.exps[K]
        monos = {tuple(int(v) for v in B[a] + B[c]) for a in range(K.size) for c in range(K.size)}
        for m, (c, lin) in amap.items():
            lin = {d: a for d, a in lin.items() if d not in fixed}
            if m not in monos and (c or lin):
                rows.append((c, lin))
        maps.append(amap)
    user = [r for r in program.linear if r.role == "user"]
    for lin_rows in (r for r in user if r.kind == "eq"):
        eqs = [[-exact(b), {}] for b in lin_rows.rhs]
        for r, d, v in zip(lin_rows.rows, lin_rows.ids, lin_rows.vals):
            if int(d) not in fixed:
                eqs[r][1][int(d)] = eqs[r][1].get(int(d), 0) + exact(v)
        rows += [(c, lin) for c, lin in eqs]
    delta = exact_correction(rows, xq)
    if delta is None:
        return None, None, "the equality rows cannot be satisfied exactly (inconsistent)"
    for d, v in delta.items():
        xq[d] += v
    gram = lambda psd: exact_gram([xq[int(d)] for d in psd.ids], psd.size)  # noqa: E731
    margins, owned = {}, set()
    for con, amap in zip(program.sos_constraints, maps):
        owned.add(id(con.psd))
        K = face(con.psd)
        Q = gram(con.psd)
        residual = exact_sub(evaluate_affine(amap, xq), gram_form(con.basis.exps, Q))
        QK, missing = absorb_residual(con.basis.exps[K], Q[np.ix_(K, K)], residual)
        if QK is None:
            return None, None, (f"constraint {con.name!r}: the residual on monomial {missing} cannot "
                                "be absorbed by the Gram basis")
        lb = proven_min_eig(QK)
        if lb is None:
            return None, None, f"constraint {con.name!r}: its Gram matrix is not provably PSD"
        margins[con.name] = lb
    for b in program.blocks:
        if b.psd is None or id(b.psd) in owned:
            continue
        K = face(b.psd)
        S = gram(b.psd)[np.ix_(K, K)]
        if b.psd.cone == "dsos":
            lb = min((S[i, i] - sum(abs(S[i, j]) for j in range(K.size) if j != i)
                      for i in range(K.size)), default=Fraction(0))
            lb = float_down(lb) if lb >= 0 else None
        else:
            lb = proven_min_eig(S)
        if lb is None:
            return None, None, f"{b.psd.role} block {b.name!r} is not provably in its cone"
        margins[b.name] = lb
    for lin_rows in (r for r in user if r.kind == "ge"):
        lhs = [-exact(b) for b in lin_rows.rhs]
        for r, d, v in zip(lin_rows.rows, lin_rows.ids, lin_rows.vals):
            lhs[r] += exact(v) * xq[int(d)]
        if any(v < 0 for v in lhs):
            return None, None, f"linear constraint {lin_rows.name!r} does not hold exactly"
    return xq, margins, None


def _exact_objective(expr, xq: dict) -> Fraction:
    """The objective (affine Polynomial) at exact decision values."""
    c0, C, expr_ids = affine_rows([expr])
    return exact(c0[0]) + sum((exact(c) * xq[int(d)] for c, d in zip(C[0], expr_ids)), Fraction(0))


def _float_margin(ids, x, con, K) -> float:
    """lambda_min of Q[K, K] after absorbing the representable residual, in floats (a pre-check)."""
    p = con.poly.with_vars(con.basis.vars)
    if p.ids.size:
        p = p.assign(p.ids, x[positions(ids, p.ids)])
    Q = svec_to_matrix(x[positions(ids, con.psd.ids)], con.psd.size)
    if not K.size:
        return math.inf
    residual = {tuple(int(a) for a in e): float(c) for e, c in zip(p.exps, p.coef[:, 0])}
    for m, c in gram_form(con.basis.exps, Q).items():
        residual[m] = residual.get(m, 0.0) - c
    B = con.basis.exps[K]
    monos = {tuple(int(v) for v in B[a] + B[c]) for a in range(K.size) for c in range(K.size)}
    QK, _ = absorb_residual(B, Q[np.ix_(K, K)].astype(object),
                            {m: c for m, c in residual.items() if m in monos})
    return float(np.linalg.eigvalsh(QK.astype(float))[0])


# ---------------------------------------------------------------------- the search for a proof
def _objective_expr(program):
    sense, expr = program.objective or (None, None)
    if program.cvxpy_constraints or is_cvxpy(expr) or isinstance(expr, QuadraticForm):
        raise UnverifiedSolutionError(
            f"no rigorous bound for {program.name!r}: it needs an affine objective and no "
            "cvxpy constraints", "unverified",
            "maximize/minimize an affine expression (a new variable bounded by SOS constraints)")
    return sense, expr


def _bound_from(program, data, solver_value, sense, expr, x, method, kept, t0):
    """(the Bound proven near x, None), or (None, reason)."""
    xq, margins, reason = prove_point(program, data.ids, x, kept)
    if margins is None:
        return None, reason
    point = np.array([float(xq[int(d)]) for d in data.ids])
    if sense is None:
        return Bound(None, None, None, method, point, margins, time.perf_counter() - t0), None
    value = _exact_objective(expr, xq)
    proven = float_down(value) if sense == "max" else -float_down(-value)
    return Bound(sense, solver_value, proven, method, point, margins, time.perf_counter() - t0), None


def confirm(program, data, x, kept: dict, solver_x) -> Bound | None:
    """The exact certificate at a point x the floating-point judge proved (:mod:`.proof`, on the
    faces ``kept``), or None: each multiplier block raised to S + mu I with a proven lambda_min >= 0
    (as the judge does), then :func:`prove_point` on those faces. Rigorous mode starts here."""
    t0 = time.perf_counter()
    sense, expr = _objective_expr(program)
    y = x.copy()
    owned = {id(psd) for con in program.sos_constraints for _, psd in con.gram_blocks}
    for b in program.blocks:
        if b.psd is None or id(b.psd) in owned or not b.psd.size or b.psd.role != "multiplier":
            continue
        pos = positions(data.ids, b.ids)
        lam = eig_lower(svec_to_matrix(y[pos], b.psd.size))
        if lam < 0:
            i, j = svec_pairs(b.psd.size)
            y[pos[i == j]] += -lam * (1 + 1e-6) + 1e-300
    solver_value = float(objective_value(data, solver_x)) if sense else None
    found, _ = _bound_from(program, data, solver_value, sense, expr, y, "exact at the proven point", kept, t0)
    return found


def _diagonals(program, ids, x) -> dict:
    return {id(b.psd): np.diag(svec_to_matrix(x[positions(ids, b.ids)], b.psd.size))
            for b in program.blocks if b.psd is not None and b.psd.size}


def _faces(program, ids, x) -> dict:
    """Kept indices of every block: diagonal entries above FACE_TOL x the block's largest
    (none if that is below FACE_TOL x the largest diagonal of all blocks)."""
    diags = _diagonals(program, ids, x)
    top = max((float(d.max()) for d in diags.values()), default=0.0)
    return {k: np.flatnonzero(d > FACE_TOL * d.max()) if d.max() > FACE_TOL * top
            else np.zeros(0, dtype=np.int64) for k, d in diags.items()}


def prove_bound(program, data, x, tightenings=TIGHTENINGS, solver_x=None) -> Bound:
    """The objective of ``program`` proven exactly near the point x (module doc); ``solver_x`` (default
    x) is the solver's point, whose objective the Bound reports beside the proven one.

    ``data`` is the conic data x belongs to. Raises UnverifiedSolutionError naming what could
    not be proven (the last two attempts).
    """
    t0 = time.perf_counter()
    sense, expr = _objective_expr(program)
    solver_value = float(objective_value(data, x if solver_x is None else solver_x)) if sense else None
    kept = _faces(program, data.ids, x)
    reasons = []
    for candidate, method in _shift_candidates(program, data.ids, x, sense, expr, kept):
        found, reason = _bound_from(program, data, solver_value, sense, expr, candidate, method, kept, t0)
        if found is not None:
            return found
        reasons.append(f"{method}: {reason}")
    # eps relative to each block's largest diagonal, at least the solvers' absolute scale 1
    scales = {k: max(float(d.max()), 1.0) for k, d in _diagonals(program, data.ids, x).items()}
    for rel in tightenings:
        tight = program.tightened(kept, {k: rel * v for k, v in scales.items()})
        sol = tight.solve(prove=False, tol_feas=1e-10, tol_gap_abs=1e-10, tol_gap_rel=1e-10)
        if sol.status not in ANSWERED or not np.isfinite(sol.x).all():
            reasons.append(f"tightened by {rel:.0e}: {sol.status}")
            continue
        found, reason = _bound_from(program, data, solver_value, sense, expr, sol.values_of(data.ids),
                                    f"tightened ({rel:.0e})", kept, t0)
        if found is not None:
            return found
        reasons.append(f"tightened by {rel:.0e}: {reason}")
    raise UnverifiedSolutionError(
        f"no rigorous bound could be proven for {program.name!r}: {'; '.join(reasons[-2:])}",
        "unverified", "a program with strictly feasible points (an interior), tighter solver "
        "tolerances, or prog.solve() without rigorous=True for the verified numerical value")


def _shift_candidates(program, ids, x0, sense, expr, kept):
    """Decision vectors of the ``shift`` path (module docstring), most promising first."""
    if sense is None:
        yield x0, "as solved"
        return
    c0, C, expr_ids = affine_rows([expr])
    nz = np.flatnonzero(C[0])
    if nz.size != 1:
        return
    t = positions(ids, expr_ids[nz])[0]
    worse = -np.sign(C[0, nz[0]]) if sense == "max" else np.sign(C[0, nz[0]])
    base = x0.copy()
    owned = {id(con.psd) for con in program.sos_constraints}
    for b in program.blocks:               # raise slightly negative multiplier/variable blocks
        if b.psd is None or id(b.psd) in owned or b.psd.cone != "psd" or not b.psd.size:
            continue
        pos = positions(ids, b.ids)
        K = kept[id(b.psd)]
        S = svec_to_matrix(base[pos], b.psd.size)[np.ix_(K, K)]
        need = 1e-12 * b.psd.size * max(1.0, float(np.abs(S).max(initial=0.0)))
        lam = float(np.linalg.eigvalsh(S)[0]) if K.size else math.inf
        if lam < need:
            i, j = svec_pairs(b.psd.size)
            base[pos[(i == j) & np.isin(i, K)]] += 2 * (need - lam)
    size, tries = max(1.0, abs(float(base[t]))), 2
    for k in range(int(np.log2(SHIFT_MAX / 1e-13)) + 2):
        eps = 0.0 if k == 0 else 1e-13 * size * 2.0 ** (k - 1)
        x = base.copy()
        x[t] += worse * eps
        if all(_float_margin(ids, x, con, kept[id(con.psd)]) > 1e-13 * max(1, con.psd.size)
               * max(1.0, float(np.abs(x[positions(ids, con.psd.ids)]).max(initial=0.0)))
               for con in program.sos_constraints):
            yield x, f"shift ({eps:.1e})"
            tries -= 1
            if not tries:
                return

"""Solutions of SOS programs: the independent check of the whole certificate, rigorous bounds.

The rule: no number leaves a Solution (``value``, ``objective``, ``gram_matrix``) unless
the whole certificate passes ``verify()``, whatever status the solver reported.

``verify()`` does not reuse the coefficient-matching matrix the solver saw. For every SOS
constraint it rebuilds z^T Q z from the basis by polynomial arithmetic and compares it with
the constraint's polynomial at the solution; it checks every Gram block -- SOS constraints,
SOS-matrix constraints, families, the multipliers of ``add_nonneg_on``, ``new_sos`` and
``new_psd`` blocks -- for Q >= 0 (smallest eigenvalue) or, for DSOS blocks, diagonal
dominance Q_ii >= sum_j |Q_ij| as numbers; and every linear equality and inequality. With
e = p - z^T Q z and every monomial of e in the Gram monomial set, p = z^T (Q + E) z with
||E||_2 <= sqrt(2) ||e||_2, so lambda_min(Q) >= sqrt(2) ||e||_2 proves p SOS (up to
floating point) -- ``strict``.

Rigorous bounds (``Solution.rigorous_bound``, ``SOSProgram.solve(rigorous=True)``) go
further: a decision vector d' is found at which every certificate holds *exactly*, in
rational arithmetic on the floats (``prove_point``, exact helpers in :mod:`.gram`):

1. facial reduction: Gram diagonals that vanish at the solver's point (below FACE_TOL
   relative) are fixed to exactly zero with their rows and columns;
2. rows no Gram matrix can absorb -- coefficients of monomials no kept z_i z_j produces
   (forced to zero by coefficient matching) and ``add_eq`` rows -- are made to hold by the
   minimum-norm exact (rational) correction of the decisions;
3. each constraint's polynomial is evaluated exactly (an ``add_nonneg_on`` one rebuilt from
   its source, multipliers and constraint polynomials), its residual absorbed into Q[K, K]
   (the exact orthogonal projection onto the matching Gram matrices), and every block proven
   positive semidefinite (``proven_min_eig``); ``add_ge`` rows must hold exactly.

The objective at d', computed exactly and rounded to the safe side, is the proven bound.
The starting point comes from

* ``shift``: the solver's point with a single-decision objective moved towards its worse
  side (maximize g s.t. p - g SOS: g lowered until Q + E stays PSD; Loefberg 2009,
  "Pre- and post-processing sum-of-squares programs in practice"), multiplier blocks with
  slightly negative eigenvalues raised by a multiple of I; or
* ``tightened``: a re-solve with every kept block tightened to Q[K, K] >= eps I (eps relative
  to the block's scale, from 1e-12 up), so the point has a margin the residual fits under.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from fractions import Fraction

import numpy as np

from ..errors import InfeasibleError, InputError, SolverError, UnverifiedSolutionError
from ..poly import PolyMatrix, Polynomial
from ..poly.polynomial import MAX_COEFFICIENT
from ..poly.monomials import match_rows
from .conic import cvxpy_block_vars, positions
from .gram import (SQRT2, absorb_residual, evaluate_affine, exact, exact_affine, exact_correction,
                   exact_gram, exact_sub, float_down, gram_form, merge_affine, proven_min_eig,
                   svec_pairs, svec_to_matrix)
from .objective import QuadraticForm, affine_rows, is_cvxpy

_HINTS = {
    "infeasible": "a higher degree (a richer Gram basis or multipliers), or check that the "
                  "statement is true: an SOS relaxation can be infeasible although the "
                  "polynomial inequality holds",
    "unbounded": "bound the objective (add constraints) or check its sign (maximize vs minimize)",
    "solver_error": "keep scale=True, rescale the data (coefficients of very different "
                    "magnitudes), lower the degree, or backend='cvxpy' with another installed solver",
}
_UNVERIFIED_HINTS = {
    "SCS": "solver='CLARABEL' (the default interior-point solver, far more accurate than SCS), "
           "or tighter SCS tolerances (eps=1e-9, max_iters=100000)",
    None: "tighter solver tolerances (Clarabel: tol_feas=1e-10, tol_gap_abs=1e-10, "
          "tol_gap_rel=1e-10), rescale the problem data, or give the program more margin "
          "(a small positive margin in strict inequalities, a lower degree)",
}
_ANSWERED = ("optimal", "optimal_inaccurate")
FACE_TOL = 1e-7          # rigorous bounds: a Gram diagonal below this (relative) is taken as 0
TIGHTENINGS = (1e-12, 3e-12, 1e-11, 3e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6)  # rigorous: Q >= eps I (relative)
SHIFT_MAX = 1e-7         # rigorous bounds: largest relative shift tried before tightening


def unverified_hint(solver: str) -> str:
    """What to try when a solver's answer fails the independent check."""
    return _UNVERIFIED_HINTS.get(solver, _UNVERIFIED_HINTS[None])


# ---------------------------------------------------------------------- the independent check
@dataclass
class CertificateCheck:
    """Numbers that say whether one block of a certificate holds.

    ``kind``: the constraint kind ("sos", "sos_matrix", "nonneg_on") for a Gram block with a
    coefficient identity; "multiplier", "sos_var", "psd_var" for a block that must only be
    in its cone; "eq", "ge", "cvxpy" for linear or cvxpy constraints (``basis_size`` is then
    the number of rows, ``residual`` the largest violation, ``rel_residual`` relative to the
    row's scale). ``reason`` says what failed and by how much.
    """

    name: str
    kind: str
    basis_size: int
    min_eig: float
    residual: float          # max |coefficient| of p - z^T Q z (or max row violation)
    rel_residual: float      # residual / max |coefficient of p| (or per-row scale)
    strict: bool             # lambda_min(Q) >= sqrt2 ||e||_2 with e representable
    passed: bool
    cone: str = "psd"
    dd_margin: float = math.nan   # min_i Q_ii - sum_{j != i} |Q_ij| (DSOS blocks)
    reason: str = ""


def _cone_check(Q, cone, eig_tol):
    """(min eig, dd margin, ok, reason) of a Gram block in its cone."""
    min_eig = float(np.linalg.eigvalsh(Q).min()) if Q.size else 0.0
    tol = eig_tol * max(1.0, float(np.abs(Q).max(initial=0.0)))
    if cone == "dsos":
        dd = float((np.diag(Q) - (np.abs(Q).sum(axis=1) - np.abs(np.diag(Q)))).min()) if Q.size else 0.0
        ok = dd >= -tol
        reason = "" if ok else f"diagonal dominance violated by {-dd:.2e} (tolerance {tol:.1e})"
        return min_eig, dd, ok, reason
    ok = min_eig >= -tol
    reason = "" if ok else f"min eigenvalue {min_eig:.3e} below -{tol:.1e}"
    return min_eig, math.nan, ok, reason


def check_gram(name, kind, p, basis_exps, Q, eig_tol=1e-7, rel_tol=1e-6, cone="psd") -> CertificateCheck:
    """Check p = z^T Q z and Q in its cone for a numeric polynomial p and basis exponents."""
    min_eig, dd, cone_ok, reason = _cone_check(Q, cone, eig_tol)
    B = basis_exps
    zQz = Polynomial(p.vars, (B[:, None, :] + B[None, :, :]).reshape(-1, B.shape[1]), Q.ravel())
    e = p - zQz
    scale = max(1.0, float(np.abs(p.coef).max(initial=0.0)))
    res = float(np.abs(e.coef).max(initial=0.0))
    representable = bool((match_rows(zQz.exps, e.exps) >= 0).all()) if e.nterms else True
    strict = representable and min_eig >= np.sqrt(2.0) * float(np.linalg.norm(e.coef))
    res_ok = res <= rel_tol * scale
    if not res_ok:
        reason = "; ".join(r for r in (reason, f"coefficient residual {res:.2e} above "
                                       f"{rel_tol:.0e} x {scale:.3g}") if r)
    return CertificateCheck(name, kind, B.shape[0], min_eig, res, res / scale, bool(strict),
                            bool(cone_ok and res_ok), cone, dd, reason)


def check_block(name, kind, Q, cone="psd", eig_tol=1e-7) -> CertificateCheck:
    """Check a block that must only lie in its cone (multipliers, new_sos, new_psd)."""
    min_eig, dd, ok, reason = _cone_check(Q, cone, eig_tol)
    return CertificateCheck(name, kind, Q.shape[0], min_eig, 0.0, 0.0, bool(min_eig > 0), bool(ok),
                            cone, dd, reason)


def check_linear(rows, ids, x, tol) -> CertificateCheck:
    """Check ``rows`` (a LinearRows) at the values x of ``ids``: violation <= tol x row scale."""
    n = rows.rhs.size
    terms = rows.vals * x[positions(ids, rows.ids, f"constraint {rows.name!r}")]
    lhs = np.bincount(rows.rows, weights=terms, minlength=n)
    size = np.bincount(rows.rows, weights=np.abs(terms), minlength=n)
    r = lhs - rows.rhs
    viol = np.abs(r) if rows.kind == "eq" else np.maximum(-r, 0.0)
    rel = viol / np.maximum(1.0, np.maximum(np.abs(rows.rhs), size))
    worst = float(rel.max(initial=0.0))
    ok = worst <= tol
    reason = "" if ok else (f"row {int(rel.argmax())} violated by {float(viol.max()):.2e} "
                            f"(relative {worst:.2e} above {tol:.0e})")
    return CertificateCheck(rows.name, rows.kind, n, math.nan, float(viol.max(initial=0.0)), worst,
                            False, bool(ok), "", math.nan, reason)


@dataclass
class VerificationReport:
    """Independent check of every block of a solution's certificate (module docstring)."""

    checks: list
    linear_residual: float
    passed: bool

    @property
    def failures(self) -> list:
        return [c for c in self.checks if not c.passed]

    @property
    def min_eig(self) -> float:
        return min((c.min_eig for c in self.checks if not math.isnan(c.min_eig)), default=np.inf)

    @property
    def max_residual(self) -> float:
        return max((c.residual for c in self.checks if c.kind not in ("eq", "ge", "cvxpy")), default=0.0)

    def summary(self) -> str:
        """One line per failing block: its name, kind and by how much it fails."""
        if self.passed:
            return "every block passes"
        return "; ".join(f"{c.kind} {c.name!r}: {c.reason}" for c in self.failures)

    def as_dict(self) -> dict:
        return {"passed": self.passed, "min_eig": self.min_eig, "max_residual": self.max_residual,
                "linear_residual": self.linear_residual, "checks": [asdict(c) for c in self.checks]}

    def __str__(self) -> str:
        lines = [f"{'block':<20} {'kind':<10} {'size':>5} {'min eig':>11} {'residual':>10} ok"]
        for c in self.checks:
            eig = "-" if math.isnan(c.min_eig) else f"{c.min_eig:.3e}"
            lines.append(f"{c.name:<20} {c.kind:<10} {c.basis_size:>5} {eig:>11} "
                         f"{c.residual:>10.2e} {'yes' if c.passed else 'NO: ' + c.reason}")
        lines.append(f"linear constraints residual {self.linear_residual:.2e}; "
                     f"{'PASSED' if self.passed else 'FAILED'}")
        return "\n".join(lines)


# ---------------------------------------------------------------------- rigorous bounds
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
    c0, C, dec = affine_rows([expr])
    return exact(c0[0]) + sum((exact(c) * xq[int(d)] for c, d in zip(C[0], dec)), Fraction(0))


def _float_margin(ids, x, con, K) -> float:
    """lambda_min of Q[K, K] after absorbing the representable residual, in floats (a pre-check)."""
    p = con.poly.with_vars(con.basis.vars)
    if p.dec.size:
        p = p.assign(p.dec, x[positions(ids, p.dec)])
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


class Solution:
    """The outcome of ``SOSProgram.solve``: status, values, certificates, timings.

    ``status`` is what the solver said; ``verified`` whether the whole certificate passes
    the independent check; ``outcome`` combines them ("verified", "unverified" or the
    failure status). Every accessor that hands out numbers (``value``, ``objective``,
    ``gram_matrix``) raises unless ``verified``; ``values_of`` is the unchecked diagnostic.
    """

    def __init__(self, program, data, status, x, solver, backend, timings, raw_status="", info=None,
                 reason=None):
        self.program, self.data = program, data
        self.status, self.x = status, x
        self.solver, self.backend = solver, backend
        self.timings = timings
        self.raw_status, self.info, self.reason = raw_status, info or {}, reason
        self.rigorous = False
        self.program_version = getattr(program, "version", None)
        self._report = None
        self._bound = None
        self._bound_error = None

    # ------------------------------------------------------------------ status
    @property
    def verified(self) -> bool:
        """The solver gave an answer and its whole certificate passes ``verify()``."""
        return self.status in _ANSWERED and self.verify().passed

    usable = verified        # the name the learner uses

    @property
    def outcome(self) -> str:
        """"verified", "unverified" (an answer whose certificate fails) or the failure status."""
        if self.status not in _ANSWERED:
            return self.status
        return "verified" if self.verify().passed else "unverified"

    def raise_for_status(self) -> "Solution":
        """Raise a typed error, with what to try, unless the solution is verified.

        In rigorous mode the bound must also be proven (see ``rigorous_bound``).
        """
        self._raise_unless_verified()
        if self.rigorous:
            self.rigorous_bound()
        return self

    def _raise_unless_verified(self):
        if self.verified:
            return
        detail = f" ({self.reason})" if self.reason else f" (solver said {self.raw_status!r})"
        if self.status == "infeasible":
            raise InfeasibleError(f"program {self.program.name!r} is infeasible{detail}.",
                                  "infeasible", _HINTS["infeasible"])
        if self.status in _ANSWERED:
            report = self.verify()
            raise UnverifiedSolutionError(
                f"the {self.solver} answer to {self.program.name!r} (solver status {self.status}) "
                f"fails the independent check, so no number from it is returned: "
                f"{report.summary()}.\n{report}", "unverified", unverified_hint(self.solver), report)
        raise SolverError(f"solving {self.program.name!r} failed: status {self.status}{detail}.",
                          self.status, _HINTS.get(self.status))

    # ------------------------------------------------------------------ values
    def values_of(self, ids) -> np.ndarray:
        """Values of decision ids as the solver returned them (unchecked: for diagnostics)."""
        return self.x[positions(self.data.ids, np.asarray(ids, dtype=np.int64))]

    def _point(self) -> np.ndarray:
        """The decision vector handed out: the proven one in rigorous mode."""
        return self.rigorous_bound().x if self.rigorous else self.x

    def _assign(self, p: Polynomial, x=None) -> Polynomial:
        x = self._point() if x is None else x
        return p.assign(p.dec, x[positions(self.data.ids, p.dec)]) if p.dec.size else p

    def value(self, item):
        """Numbers for a decision expression: float, numeric Polynomial, ndarray or PolyMatrix.

        Raises InfeasibleError / UnverifiedSolutionError / SolverError unless verified.
        """
        self.raise_for_status()
        if isinstance(item, Polynomial):
            p = self._assign(item)
            return p.constant_value() if p.is_constant else p
        if isinstance(item, PolyMatrix):
            m = item.map(self._assign)
            if all(e.is_constant for e in m.entries.flat):
                return np.vectorize(lambda e: e.constant_value(), otypes=[float])(m.entries)
            return m
        if isinstance(item, QuadraticForm):
            return item.value(self._point()[positions(self.data.ids, item.dec)])
        if is_cvxpy(item):
            return item.value
        raise TypeError(f"cannot take the value of {type(item).__name__}")

    def gram_matrix(self, item, checked: bool = True) -> np.ndarray:
        """The Gram matrix of a constraint or multiplier (anything with a ``psd`` block).

        Raises unless verified; ``checked=False`` returns the solver's numbers anyway
        (diagnostics only).
        """
        if checked:
            self.raise_for_status()
        x = self._point() if checked else self.x
        return svec_to_matrix(x[positions(self.data.ids, item.psd.ids)], item.psd.size)

    @property
    def objective(self) -> float:
        """Objective value in the user's sense (maximise -> the maximum); proven if rigorous."""
        self.raise_for_status()
        sense, expr = self.program.objective or ("min", None)
        if is_cvxpy(expr):
            return float(self.info.get("objective"))
        if self.rigorous and self.rigorous_bound().proven is not None:
            return self.rigorous_bound().proven
        return self._solver_objective()

    def _solver_objective(self) -> float:
        d = self.data
        val = self.x @ d.q + d.c + (self.x @ (d.P @ self.x) if d.P is not None else 0.0)
        return -val if d.sense == "max" else val

    @property
    def bound(self) -> Bound:
        """The rigorous bound (``rigorous_bound()``)."""
        return self.rigorous_bound()

    # ------------------------------------------------------------------ certificates
    def verify(self, eig_tol: float = 1e-7, rel_tol: float = 1e-6) -> VerificationReport:
        """Independent numerical check of every block of the certificate (module docstring).

        Linear rows are allowed 10 x ``rel_tol`` relative to each row's scale.
        """
        if self._report is not None and (eig_tol, rel_tol) == (1e-7, 1e-6):
            return self._report
        report = self._verify(eig_tol, rel_tol)
        if (eig_tol, rel_tol) == (1e-7, 1e-6):
            self._report = report
        return report

    def _require_unchanged(self, what: str):
        if self.program_version != getattr(self.program, "version", None):
            raise InputError(f"{what}: program {self.program.name!r} changed after this solve "
                             "(update, set_weights or a new constraint), so its certificate cannot "
                             "be re-checked against it. Try: prog.solve() again.")

    def _verify(self, eig_tol, rel_tol) -> VerificationReport:
        self._require_unchanged("verify")
        x = self.x
        if not np.abs(x).max(initial=0.0) <= MAX_COEFFICIENT:     # polynomials refuse such numbers
            bad = CertificateCheck("solution", "vector", int(x.size), math.nan, math.inf, math.inf,
                                   False, False, "", math.nan, "non-finite entries (or entries above "
                                   f"{MAX_COEFFICIENT:.0e}) in the solution")
            return VerificationReport([bad], math.inf, False)
        ids = self.data.ids
        at = lambda dec: x[positions(ids, dec)]  # noqa: E731
        checks, owned = [], set()
        for con in self.program.sos_constraints:
            owned.add(id(con.psd))
            Q = svec_to_matrix(at(con.psd.ids), con.psd.size)
            p = self._assign(con.poly.with_vars(con.basis.vars), x)
            checks.append(check_gram(con.name, con.kind, p, con.basis.exps, Q, eig_tol, rel_tol, con.psd.cone))
        for b in self.program.blocks:
            if b.psd is not None and id(b.psd) not in owned:
                Q = svec_to_matrix(at(b.psd.ids), b.psd.size)
                checks.append(check_block(b.name, b.psd.role, Q, b.psd.cone, eig_tol))
        linear = [check_linear(rows, ids, x, 10 * rel_tol) for rows in self.program.linear
                  if rows.role == "user"]
        linear += self._check_cvxpy(10 * rel_tol)
        checks += linear
        lin = max((c.residual for c in linear), default=0.0)
        return VerificationReport(checks, lin, all(c.passed for c in checks))

    def _check_cvxpy(self, tol) -> list:
        """cvxpy constraints, evaluated at this solution's values."""
        if not self.program.cvxpy_constraints:
            return []
        for b, var in zip(self.program.blocks, cvxpy_block_vars(self.program)):
            var.value = self.x[positions(self.data.ids, b.ids)]
        out = []
        for k, c in enumerate(self.program.cvxpy_constraints):
            viol = float(np.max(c.violation()))
            scale = max([1.0] + [float(np.abs(a.value).max()) for a in c.args if a.value is not None])
            ok = viol <= tol * scale
            out.append(CertificateCheck(f"cvxpy[{k}]", "cvxpy", int(np.size(c.violation())), math.nan, viol,
                                        viol / scale, False, bool(ok), "", math.nan,
                                        "" if ok else f"violated by {viol:.2e}"))
        return out

    # ------------------------------------------------------------------ rigorous bounds
    def rigorous_bound(self) -> Bound:
        """The objective value proven exactly (module docstring); cached.

        Raises UnverifiedSolutionError when the solution is not verified or no proof was
        found (the message says which block could not be proven).
        """
        if self._bound is not None:
            return self._bound
        if self._bound_error is not None:
            raise self._bound_error
        self._raise_unless_verified()
        t0 = time.perf_counter()
        try:
            self._bound = self._prove()
        except UnverifiedSolutionError as exc:
            self._bound_error = exc
            raise
        finally:
            self.timings["rigorous"] = time.perf_counter() - t0
        return self._bound

    def _objective_expr(self):
        sense, expr = self.program.objective or (None, None)
        if self.program.cvxpy_constraints or is_cvxpy(expr) or isinstance(expr, QuadraticForm):
            raise UnverifiedSolutionError(
                f"no rigorous bound for {self.program.name!r}: it needs an affine objective and no "
                "cvxpy constraints", "unverified",
                "maximize/minimize an affine expression (a new variable bounded by SOS constraints)")
        return sense, expr

    def _bound_from(self, sense, expr, x, method, kept, t0):
        """(the Bound proven near x, None), or (None, reason)."""
        xq, margins, reason = prove_point(self.program, self.data.ids, x, kept)
        if margins is None:
            return None, reason
        point = np.array([float(xq[int(d)]) for d in self.data.ids])
        if sense is None:
            return Bound(None, None, None, method, point, margins, time.perf_counter() - t0), None
        exact = _exact_objective(expr, xq)
        proven = float_down(exact) if sense == "max" else -float_down(-exact)
        return Bound(sense, float(self._solver_objective()), proven, method, point, margins,
                     time.perf_counter() - t0), None

    def _diagonals(self, x) -> dict:
        return {id(b.psd): np.diag(svec_to_matrix(x[positions(self.data.ids, b.ids)], b.psd.size))
                for b in self.program.blocks if b.psd is not None and b.psd.size}

    def _faces(self, x) -> dict:
        """Kept indices of every block: diagonal entries above FACE_TOL x the block's largest
        (none if that is below FACE_TOL x the largest diagonal of all blocks)."""
        diags = self._diagonals(x)
        top = max((float(d.max()) for d in diags.values()), default=0.0)
        return {k: np.flatnonzero(d > FACE_TOL * d.max()) if d.max() > FACE_TOL * top
                else np.zeros(0, dtype=np.int64) for k, d in diags.items()}

    def _prove(self) -> Bound:
        self._require_unchanged("rigorous_bound")
        t0 = time.perf_counter()
        sense, expr = self._objective_expr()
        kept = self._faces(self.x)
        reasons = []
        for x, method in self._shift_candidates(sense, expr, kept):
            found, reason = self._bound_from(sense, expr, x, method, kept, t0)
            if found is not None:
                return found
            reasons.append(f"{method}: {reason}")
        # eps relative to each block's largest diagonal, at least the solvers' absolute scale 1
        scales = {k: max(float(d.max()), 1.0) for k, d in self._diagonals(self.x).items()}
        for rel in TIGHTENINGS:
            tight = self.program.tightened(kept, {k: rel * v for k, v in scales.items()})
            sol = tight.solve(tol_feas=1e-10, tol_gap_abs=1e-10, tol_gap_rel=1e-10)
            if sol.status not in _ANSWERED or not np.isfinite(sol.x).all():
                reasons.append(f"tightened by {rel:.0e}: {sol.status}")
                continue
            found, reason = self._bound_from(sense, expr, sol.values_of(self.data.ids),
                                             f"tightened ({rel:.0e})", kept, t0)
            if found is not None:
                return found
            reasons.append(f"tightened by {rel:.0e}: {reason}")
        raise UnverifiedSolutionError(
            f"no rigorous bound could be proven for {self.program.name!r}: {'; '.join(reasons[-2:])}",
            "unverified", "a program with strictly feasible points (an interior), tighter solver "
            "tolerances, or prog.solve() without rigorous=True for the verified numerical value")

    def _shift_candidates(self, sense, expr, kept):
        """Decision vectors of the ``shift`` path (module docstring), most promising first."""
        if sense is None:
            yield self.x, "as solved"
            return
        c0, C, dec = affine_rows([expr])
        nz = np.flatnonzero(C[0])
        if nz.size != 1:
            return
        ids = self.data.ids
        t = positions(ids, dec[nz])[0]
        worse = -np.sign(C[0, nz[0]]) if sense == "max" else np.sign(C[0, nz[0]])
        base = self.x.copy()
        owned = {id(con.psd) for con in self.program.sos_constraints}
        for b in self.program.blocks:          # raise slightly negative multiplier/variable blocks
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
                   for con in self.program.sos_constraints):
                yield x, f"shift ({eps:.1e})"
                tries -= 1
                if not tries:
                    return

    def __repr__(self) -> str:
        t = ", ".join(f"{k} {v * 1e3:.1f} ms" for k, v in self.timings.items())
        try:
            outcome = self.outcome
        except InputError:                  # the program changed before any check was made
            outcome = "unchecked"
        return (f"Solution(status={self.status!r}, outcome={outcome!r}, solver={self.solver}, "
                f"backend={self.backend}, {t})")

"""The independent check of a solver's answer: numbers, not the solver's own matching matrix.

For every SOS constraint, :func:`verify_certificate` rebuilds z^T Q z from the basis by
polynomial arithmetic and compares it with the constraint's polynomial at the decision values
(:func:`check_gram`); it checks every Gram block -- SOS constraints, SOS-matrix constraints,
families, the multipliers of ``add_nonneg_on``, ``new_sos`` and ``new_psd`` blocks -- for
Q >= 0 (smallest eigenvalue) or, for DSOS blocks, diagonal dominance Q_ii >= sum_j |Q_ij| as
numbers (:func:`check_block`; an SDSOS block is checked for Q >= 0 like a PSD one); and every
linear equality and inequality (:func:`check_linear`) and cvxpy constraint. Tolerances are
relative (max |Q_ij|, |p_a|), with the absolute floor 1 only as large as the program's own
numbers (:func:`tolerance_scale`).

This is a *screen*: it says whether the solver answered this program to its tolerances, so its
numbers are a usable approximation (``Solution.usable``). It proves nothing -- at the optimum of
a bound program a Gram block is singular and the identity holds only to the solver's tolerance.
What is proven is decided by :mod:`.proof` (floating point with rounding bounds) at a point
:mod:`.proven` finds; :func:`check_gram` of a given certificate runs that proof too
(docs/sos-semantics.md). Each check still reports the block's ``margin``: with e = p - z^T Q z on
the Gram monomial set, p = z^T (Q + E) z for the smallest such E and lambda_min(Q) - ||E||_F
bounds lambda_min(Q + E) from below.

The monomial structure of z^T Q z against p (:class:`GramStructure`: where each product
z_i z_j and each monomial of p lands in their union) depends only on the basis and on p's
monomials, so it is computed once per (basis, monomials) and reused by every later check of
a re-solved program (and per constraint while its monomials stay, compared by value); the
numbers -- Q, p at x, e, lambda_min(Q) -- are recomputed every time.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import asdict, dataclass, replace
from weakref import WeakKeyDictionary

import numpy as np

from ..errors import PolynomialError
from ..poly import MAX_COEFFICIENT, unique_rows
from .conic import cvxpy_block_vars, positions
from .gram import svec_to_matrix
from .proof import prove_gram


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
    margin: float            # lambda_min(Q) - ||E||_F (-inf when e has a monomial z^T Q z cannot give)
    passed: bool
    cone: str = "psd"
    dd_margin: float = math.nan   # min_i Q_ii - sum_{j != i} |Q_ij| (DSOS blocks)
    reason: str = ""
    proven: bool | None = None    # check_gram: the identity proven (proof.prove_gram); None: not asked


def tolerance_scale(largest: float, program_scale=None) -> float:
    """The number a relative tolerance multiplies: max(largest, u), u = min(1, the program's
    largest Gram entry) -- 1 for programs of ordinary size (so their tolerances are as they
    were), the program's own size for tiny ones (-1e-9 x^2 is judged on the scale 1e-9)."""
    return max(largest, 1.0 if program_scale is None else min(1.0, program_scale))


def _cone_check(Q, cone, eig_tol, scale):
    """(min eig, dd margin, ok, reason) of a Gram block in its cone ("psd" and "sdsos": Q >= 0),
    to eig_tol x ``scale`` (:func:`tolerance_scale`)."""
    min_eig = float(np.linalg.eigvalsh(Q).min()) if Q.size else 0.0
    tol = eig_tol * scale
    if cone == "dsos":
        dd = float((np.diag(Q) - (np.abs(Q).sum(axis=1) - np.abs(np.diag(Q)))).min()) if Q.size else 0.0
        ok = dd >= -tol
        reason = "" if ok else f"diagonal dominance violated by {-dd:.2e} (tolerance {tol:.1e})"
        return min_eig, dd, ok, reason
    ok = min_eig >= -tol
    reason = "" if ok else f"min eigenvalue {min_eig:.3e} below -{tol:.1e}"
    return min_eig, math.nan, ok, reason


@dataclass(frozen=True)
class GramStructure:
    """Monomials of p and of z z^T in their union U (rows of neither are repeated).

    ``p_at[r]``: the row of U of p's monomial r; ``pair_at[i * N + j]``: the row of U of
    z_i z_j (N = basis size); ``in_gram[u]``: some z_i z_j is the monomial u. Over several
    blocks (:func:`check_blocks_values`) ``pair_at`` runs over every block's N_k^2 products in
    turn and ``first_block[u]`` is the first block producing u (-1: none)."""

    p_at: np.ndarray
    pair_at: np.ndarray
    in_gram: np.ndarray
    first_block: np.ndarray | None = None


def gram_structure(p_exps, basis_exps) -> GramStructure:
    """The :class:`GramStructure` of p's exponent rows (distinct) against the basis rows."""
    B = basis_exps
    pairs = (B[:, None, :] + B[None, :, :]).reshape(-1, B.shape[1])
    U, inv = unique_rows(np.vstack([p_exps, pairs]))
    inv = np.asarray(inv).ravel()
    in_gram = np.zeros(U.shape[0], dtype=bool)
    in_gram[inv[p_exps.shape[0]:]] = True
    parts = (inv[:p_exps.shape[0]].copy(), inv[p_exps.shape[0]:].copy(), in_gram)
    for a in parts:
        a.flags.writeable = False                   # shared by every later check (cached)
    return GramStructure(*parts)


_STRUCTURES: OrderedDict = OrderedDict()      # (ids of the arrays) -> (arrays, structure), bounded
_STRUCTURES_KEPT = 256


def cached_gram_structure(p_exps, basis_exps) -> GramStructure:
    """:func:`gram_structure`, remembered for the last few hundred (p, basis) exponent arrays.

    Exponent arrays are never changed in place; an entry keeps its arrays alive, so their ids
    cannot be reused by other arrays while it is kept."""
    key = (id(p_exps), id(basis_exps))
    hit = _STRUCTURES.get(key)
    if hit is not None and hit[0] is p_exps and hit[1] is basis_exps:
        _STRUCTURES.move_to_end(key)
        return hit[2]
    out = gram_structure(p_exps, basis_exps)
    _STRUCTURES[key] = (p_exps, basis_exps, out)
    if len(_STRUCTURES) > _STRUCTURES_KEPT:
        _STRUCTURES.popitem(last=False)
    return out


_BY_CONSTRAINT: WeakKeyDictionary = WeakKeyDictionary()   # constraint -> (p exps, basis exps, structure)


def constraint_gram_structure(con, p_exps) -> GramStructure:
    """:func:`cached_gram_structure` of a constraint's current polynomial, also remembered per
    constraint while its monomials (compared by value) and its basis (the same array) stay:
    a family re-solved with new weights builds a new polynomial with the same monomials."""
    memo = _BY_CONSTRAINT.get(con)
    if memo is not None and memo[1] is con.basis.exps and np.array_equal(memo[0], p_exps):
        return memo[2]
    out = cached_gram_structure(p_exps, con.basis.exps)
    _BY_CONSTRAINT[con] = (p_exps, con.basis.exps, out)
    return out


def check_gram(name, kind, p, basis_exps, Q, eig_tol=1e-7, rel_tol=1e-6, cone="psd") -> CertificateCheck:
    """Check a given certificate: p = z^T Q z and Q in its cone for a numeric polynomial p and
    basis exponents, to the tolerances *and* proven (:func:`~.proof.prove_gram`: the residual
    absorbed within a proven eigenvalue margin, or exactly in rational arithmetic): ``passed``
    only if both hold, at any scale of the coefficients."""
    if p.ids.size:
        raise PolynomialError(f"check_gram needs a numeric polynomial; {name!r} has decision variables. "
                              "Try: assign the solution's values first, e.g. sol.value(p)")
    check = check_gram_values(name, kind, p.coef[:, 0], gram_structure(p.exps, basis_exps), Q,
                              eig_tol, rel_tol, cone)
    proven, why = prove_gram(p, basis_exps, Q)
    reason = check.reason if proven else "; ".join(r for r in (check.reason, f"not proven: {why}") if r)
    return replace(check, passed=bool(check.passed and proven), proven=proven, reason=reason)


def residual_gram_norms(e, structure: GramStructure, sizes) -> np.ndarray:
    """||E_k||_F per block (orders ``sizes``) of the smallest symmetric E_k with sum_k z_k^T E_k z_k
    = e (e on the Gram monomial set), e_a put in its first producing block k: E_k,ij = e_a / n_a
    for the n_a pairs of block k with z_i z_j = x^a, so ||E_k||_F^2 = sum_{a owned by k} e_a^2 / n_a."""
    block = np.repeat(np.arange(len(sizes)), np.square(sizes).astype(np.int64))
    first = np.zeros(e.size, dtype=np.int64) if structure.first_block is None else structure.first_block
    own = block == first[structure.pair_at]
    n = np.bincount(structure.pair_at[own], minlength=e.size)
    g = structure.in_gram
    return np.sqrt(np.bincount(first[g], weights=e[g] ** 2 / n[g], minlength=len(sizes)))


def check_gram_values(name, kind, p_coef, structure: GramStructure, Q, eig_tol=1e-7, rel_tol=1e-6,
                      cone="psd", scale=None) -> CertificateCheck:
    """The screen of p = z^T Q z for p given by its coefficients ``p_coef`` on the monomials of
    ``structure``.

    e = p - z^T Q z on the union U of monomials (each z_i z_j adds Q_ij to its monomial). With
    e on the Gram monomial set, p = z^T (Q + E) z exactly and lambda_min(Q + E) >=
    lambda_min(Q) - ||E||_F (:func:`residual_gram_norms`): that is the block's ``margin``,
    reported. It passes when lambda_min(Q) >= -eig_tol x max |Q_ij| and e is within ``rel_tol``
    x max |p_a| (each through :func:`tolerance_scale`, with the program's ``scale``)."""
    size = structure.in_gram.size
    e = np.bincount(structure.p_at, weights=p_coef, minlength=size) \
        - np.bincount(structure.pair_at, weights=Q.ravel(), minlength=size)
    q_scale = tolerance_scale(float(np.abs(Q).max(initial=0.0)), scale)
    scale = tolerance_scale(float(np.abs(p_coef).max(initial=0.0)), scale)
    min_eig, dd, cone_ok, reason = _cone_check(Q, cone, eig_tol, q_scale)
    res = float(np.abs(e).max(initial=0.0))
    representable = not np.any(e[~structure.in_gram] != 0.0)
    margin = (min_eig if cone != "dsos" else dd) - float(residual_gram_norms(e, structure, [Q.shape[0]])[0])
    res_ok, reason = _residual_verdict(res, rel_tol, scale, reason)
    rel = relative_residual(res, scale)
    return CertificateCheck(name, kind, Q.shape[0], min_eig, res, rel, margin if representable else -math.inf,
                            bool(cone_ok and res_ok), cone, dd, reason)


def _residual_verdict(res: float, rel_tol: float, scale: float, reason: str) -> tuple[bool, str]:
    """Whether the coefficient residual ``res`` is within ``rel_tol`` x ``scale``, and ``reason``
    extended by the residual's verdict when it is not."""
    if res <= rel_tol * scale:
        return True, reason
    return False, "; ".join(r for r in (reason, f"coefficient residual {res:.2e} above {rel_tol:.0e} x {scale:.3g}") if r)


def relative_residual(res: float, scale: float) -> float:
    """res / scale, with 0 / 0 = 0 and res / 0 = inf."""
    return res / scale if scale > 0 else (0.0 if res == 0 else math.inf)


def check_blocks_values(name, kind, p_coef, structure: GramStructure, Qs, cones, eig_tol=1e-7,
                        rel_tol=1e-6, scale=None) -> CertificateCheck:
    """:func:`check_gram_values` for p = sum_k z_k^T Q_k z_k over several Gram blocks.

    e = p - sum_k z_k^T Q_k z_k on the union U; with e_k the part of e on the monomials whose
    first producing block is k, p = sum_k z_k^T (Q_k + E_k) z_k (E_k the smallest such), so the
    margin is min_k lambda_min(Q_k) - ||E_k||_F (:func:`residual_gram_norms`), reported as in
    :func:`check_gram_values`. ``min_eig`` is the least over the blocks."""
    q_scales = [tolerance_scale(float(np.abs(Q).max(initial=0.0)), scale) for Q in Qs]
    scale = tolerance_scale(float(np.abs(p_coef).max(initial=0.0)), scale)
    parts = [_cone_check(Q, cone, eig_tol, qs) for Q, cone, qs in zip(Qs, cones, q_scales)]
    size = structure.in_gram.size
    e = np.bincount(structure.p_at, weights=p_coef, minlength=size) - np.bincount(
        structure.pair_at, weights=np.concatenate([Q.ravel() for Q in Qs] + [np.zeros(0)]), minlength=size)
    res = float(np.abs(e).max(initial=0.0))
    representable = not np.any(e[~structure.in_gram] != 0.0)
    norms = residual_gram_norms(e, structure, [Q.shape[0] for Q in Qs])
    margins = [(p[0] if cone != "dsos" else p[1]) - nk for p, cone, nk in zip(parts, cones, norms)]
    cone_ok = all(p[2] for p in parts)
    reason = "; ".join(p[3] for p in parts if p[3])
    res_ok, reason = _residual_verdict(res, rel_tol, scale, reason)
    worst = min(range(len(Qs)), key=lambda k: parts[k][0], default=None)
    rel = relative_residual(res, scale)
    return CertificateCheck(name, kind, sum(Q.shape[0] for Q in Qs), parts[worst][0] if Qs else 0.0, res,
                            rel, min(margins, default=0.0) if representable else -math.inf,
                            bool(cone_ok and res_ok), cones[0] if cones else "psd",
                            parts[worst][1] if Qs else math.nan, reason)


def check_block(name, kind, Q, cone="psd", eig_tol=1e-7, scale=None) -> CertificateCheck:
    """Check a block that must only lie in its cone (multipliers, new_sos, new_psd); tolerance
    eig_tol x max |Q_ij| through :func:`tolerance_scale` (``scale``: the program's)."""
    min_eig, dd, ok, reason = _cone_check(Q, cone, eig_tol, tolerance_scale(float(np.abs(Q).max(initial=0.0)), scale))
    return CertificateCheck(name, kind, Q.shape[0], min_eig, 0.0, 0.0, min_eig, bool(ok), cone, dd, reason)


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
                            math.nan, bool(ok), "", math.nan, reason)


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


def check_cvxpy(program, ids, x, tol) -> list:
    """The program's cvxpy constraints, evaluated at the values x of decision ``ids``."""
    if not program.cvxpy_constraints:
        return []
    for b, var in zip(program.blocks, cvxpy_block_vars(program)):
        var.value = x[positions(ids, b.ids)]
    out = []
    for k, c in enumerate(program.cvxpy_constraints):
        viol = float(np.max(c.violation()))
        scale = max([1.0] + [float(np.abs(a.value).max()) for a in c.args if a.value is not None])
        ok = viol <= tol * scale
        out.append(CertificateCheck(f"cvxpy[{k}]", "cvxpy", int(np.size(c.violation())), math.nan, viol,
                                    viol / scale, math.nan, bool(ok), "", math.nan,
                                    "" if ok else f"violated by {viol:.2e}"))
    return out


def program_scale(program, at) -> float:
    """max |Q_ij| over every Gram block of ``program`` at the decision values ``at(ids)``."""
    return max((float(np.abs(at(b.ids)).max(initial=0.0)) for b in program.blocks if b.psd is not None),
               default=0.0)


def verify_certificate(program, ids, x, eig_tol=1e-7, rel_tol=1e-6) -> VerificationReport:
    """Check every block of ``program``'s certificate at the values x of decision ``ids``.

    Gram identities within ``rel_tol`` (relative), cones within ``eig_tol``, linear rows and
    cvxpy constraints within 10 x ``rel_tol`` relative to each row's scale (module docstring).
    """
    if not np.abs(x).max(initial=0.0) <= MAX_COEFFICIENT:     # polynomials refuse such numbers
        bad = CertificateCheck("solution", "vector", int(x.size), math.nan, math.inf, math.inf,
                               math.nan, False, "", math.nan, "non-finite entries (or entries above "
                               f"{MAX_COEFFICIENT:.0e}) in the solution")
        return VerificationReport([bad], math.inf, False)
    at = lambda block_ids: x[positions(ids, block_ids)]  # noqa: E731
    checks, owned = [], set()
    scale = program_scale(program, at)
    for con in program.sos_constraints:
        owned.add(id(con.psd))
        if hasattr(con, "identity_values"):          # several Gram blocks (sparse_constraint)
            checks.append(check_blocks_values(con.name, con.kind, *con.identity_values(at), eig_tol, rel_tol,
                                              scale=scale))
            continue
        Q = svec_to_matrix(at(con.psd.ids), con.psd.size)
        p = con.poly.with_vars(con.basis.vars)
        coef = p.coef[:, 0] + p.coef[:, 1:] @ at(p.ids)               # p at x
        checks.append(check_gram_values(con.name, con.kind, coef, constraint_gram_structure(con, p.exps),
                                        Q, eig_tol, rel_tol, con.psd.cone, scale=scale))
    for b in program.blocks:
        if b.psd is not None and id(b.psd) not in owned:
            Q = svec_to_matrix(at(b.psd.ids), b.psd.size)
            checks.append(check_block(b.name, b.psd.role, Q, b.psd.cone, eig_tol, scale))
    linear = [check_linear(rows, ids, x, 10 * rel_tol) for rows in program.linear if rows.role == "user"]
    linear += check_cvxpy(program, ids, x, 10 * rel_tol)
    checks += linear
    lin = max((c.residual for c in linear), default=0.0)
    return VerificationReport(checks, lin, all(c.passed for c in checks))

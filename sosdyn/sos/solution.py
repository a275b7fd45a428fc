"""Solutions of SOS programs: status, values and Gram matrices -- only when verified.

The rule: no number leaves a Solution (``value``, ``objective``, ``gram_matrix``) unless
the whole certificate passes ``verify()`` (:mod:`.verification`), whatever status the solver
reported. In rigorous mode (``SOSProgram.solve(rigorous=True)``) every number is read at the
point where the certificate is proven exactly (:mod:`.rigorous`).

A Solution refers to the program it solved, which it never changes; a program changed later
(``update``, ``set_weights``, a new constraint: its ``version`` moved on) cannot be re-checked
against this solution. ``SOSProgram.solve`` checks it at once, so the accessors of an older
solution keep working.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import (InfeasibleError, InputError, ResourceLimitError, SolverError, UnboundedError,
                      UnverifiedSolutionError)
from ..poly import PolyMatrix, Polynomial
from .conic import assign_at, objective_value, positions
from .decomposition import SOSDecomposition, sos_decomposition
from .gram import svec_to_matrix
from .moments import Atoms, Moments, check_atoms, moments_from_dual
from .objective import QuadraticForm, is_cvxpy
from .posterior import bound_pattern, safe_point
from .rigorous import ANSWERED, QUICK_TIGHTENINGS, Bound, prove_bound
from .tightened import tightened_safe_point
from .verification import VerificationReport, verify_certificate

_HINTS = {
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
_DEFAULT_TOLS = (1e-7, 1e-6)      # verify()'s default (eig_tol, rel_tol): the cached report
QUICK_PROOF_MAX = 10_000        # Gram entries up to which a bound without float correction tries the proof
_PROVING = False                  # an exact proof (Solution._proven) is under way


def infeasible_hint(program) -> str:
    """What to try when ``program`` is infeasible, by the kind of constraints it has."""
    kinds = {c.kind for c in program.sos_constraints}
    tips = [program.hint] if program.hint else []
    if "nonneg_on" in kinds:
        tips.append("a higher multiplier degree in add_nonneg_on (degree=...), or check that the set "
                    "is not empty and the polynomial is nonnegative on it")
    if kinds & {"sos", "sos_matrix"}:
        tips.append("check that the polynomial (matrix) is nonnegative; a nonnegative polynomial need not "
                    "be SOS (Motzkin): multiply it by (1 + x1^2 + ... + xn^2), or raise the degree of the "
                    "free polynomials in it")
    if any(m.psd.role == "clique" for c in program.sos_constraints for m in c.multipliers):
        tips.append("sparsity=None (one dense Gram block): a sparse basis can be too restrictive")
    if program.objective is None and not tips:
        tips.append("check the constraints added with add_eq/add_ge for a contradiction")
    if program.objective is not None:
        tips.append("relax the constraints on the objective's variables: a required bound may be "
                    "beyond what any certificate of this degree proves")
    return "; or ".join(tips)


def unverified_hint(solver: str) -> str:
    """What to try when a solver's answer fails the independent check."""
    return _UNVERIFIED_HINTS.get(solver, _UNVERIFIED_HINTS[None])


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
        self.rigorous = False          # set by SOSProgram.solve(rigorous=True)
        self.program_version = getattr(program, "version", None)
        self._report = None
        self._bound = None
        self._bound_error = None
        self._safe = None              # (position of the bound variable, its safe value, the safe objective)

    # ------------------------------------------------------------------ status
    @property
    def verified(self) -> bool:
        """The solver gave an answer and its whole certificate passes ``verify()``."""
        return self.status in ANSWERED and self.verify().passed

    usable = verified        # the name the learner uses

    @property
    def outcome(self) -> str:
        """"verified", "unverified" (an answer whose certificate fails) or the failure status."""
        if self.status not in ANSWERED:
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
                                  "infeasible", infeasible_hint(self.program))
        if self.status == "unbounded":
            raise UnboundedError(f"program {self.program.name!r} is unbounded: the objective has no finite "
                                 f"optimum{detail}.", "unbounded", _HINTS["unbounded"])
        if self.status in ANSWERED:
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

    def _point_for(self, ids) -> np.ndarray:
        """The decision vector handed out for an expression in decision ``ids``: in a lower-bound
        program whose bound variable t is among them, t is read at its safe value (``objective``)."""
        x = self._point()
        pattern = None if self.rigorous else bound_pattern(self.program)
        if pattern is None or pattern[1] not in set(np.asarray(ids).tolist()):
            return x
        pos, t, _ = self._safe_point(pattern)
        x = x.copy()
        x[pos] = t
        return x

    def _assign(self, p: Polynomial) -> Polynomial:
        return assign_at(p, self.data.ids, self._point_for(p.ids))

    def value(self, item):
        """Numbers for a decision expression: float, numeric Polynomial, ndarray or PolyMatrix.

        In a lower-bound program (maximize t, t only in the constant term of one SOS constraint:
        ``posterior.bound_pattern``) t is read at the safe value ``objective`` is computed from,
        t - delta / a (:mod:`.posterior`), never the solver's t, which can lie above the minimum;
        UnverifiedSolutionError when no safe value exists (as ``objective``). The other
        variables are the solver's (verified) numbers. Raises InfeasibleError /
        UnverifiedSolutionError / SolverError unless verified.
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
            return item.value(self._point_for(item.ids)[positions(self.data.ids, item.ids)])
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
        """Objective value in the user's sense (maximise -> the maximum); proven if rigorous.

        A lower-bound program (maximize gamma, gamma only in the constant term of one SOS
        constraint: ``posterior.bound_pattern``) returns gamma lowered to the safe side
        (:mod:`.posterior`; at a tightened re-solve, :mod:`.tightened`, when the solver's point
        has no correction), or the exactly proven bound, else UnverifiedSolutionError;
        ``value(gamma)`` is the same number; ``solver_objective`` is the solver's."""
        self.raise_for_status()
        sense, expr = self.program.objective or ("min", None)
        if is_cvxpy(expr):
            return float(self.info.get("objective"))
        if self.rigorous and self.rigorous_bound().proven is not None:
            return self.rigorous_bound().proven
        pattern = bound_pattern(self.program)
        if pattern is None:
            return objective_value(self.data, self.x)
        return self._safe_point(pattern)[2]

    def _safe_point(self, pattern) -> tuple[int, float, float]:
        """(position of the bound variable t, its safe value, the safe objective): the posterior
        shift (:func:`~.posterior.safe_point`) at the solver's point, else at the point of a
        re-solve with every Gram block tightened (:func:`~.tightened.tightened_safe_point`), else
        the quick exact proof's point; cached, and so is the refusal when none exists."""
        if self._safe is None:
            try:
                self._safe = safe_point(self, pattern)
            except UnverifiedSolutionError as exc:   # no floating-point correction: a margin, an exact proof
                self._safe = tightened_safe_point(self, pattern) or self._proven_safe_point(pattern, exc)
        if isinstance(self._safe, UnverifiedSolutionError):
            raise self._safe
        return self._safe

    def _proven_safe_point(self, pattern, exc):
        """The quick exact proof's (position of t, t, proven bound), or the refusal to raise. Not tried
        above QUICK_PROOF_MAX Gram entries (rational arithmetic on Broyden n = 1000, 54,890
        entries, ran over 15 minutes): ``rigorous=True`` asks for it."""
        entries = sum(b.psd.size * (b.psd.size + 1) // 2 for b in self.program.blocks if b.psd is not None)
        try:
            bound = self._quick_proof() if entries <= QUICK_PROOF_MAX else None
        except (UnverifiedSolutionError, ResourceLimitError):    # no proof, or its re-solves too large
            bound = None
        if bound is None or bound.proven is None:
            return UnverifiedSolutionError(
                f"{exc.detail} (nor at a tightened re-solve, nor by a quick exact proof), so neither "
                "objective nor the value of its bound variable is returned", "unverified",
                "rigorous=True (the full exact search); solver_objective is the solver's number, which "
                f"is not a bound; or {exc.hint}")
        pos = int(positions(self.data.ids, np.array([pattern[1]], dtype=np.int64))[0])
        return pos, float(np.nextafter(bound.x[pos], -np.inf)), bound.proven

    @property
    def solver_objective(self) -> float:
        """The objective as the solver returned it (verified, not corrected; rigorous: the
        solver's value next to the proven one)."""
        self.raise_for_status()
        return objective_value(self.data, self.x)

    # ------------------------------------------------------------------ dual side
    def moments(self, con, tol: float = 1e-6) -> Moments:
        """The moments of an SOS constraint (the dual of its Gram block; :mod:`.moments`).

        Raises unless the solution is verified, and UnverifiedSolutionError unless the dual is
        a PSD moment matrix to ``tol``.
        """
        self.raise_for_status()
        if con.kind not in ("sos", "nonneg_on") or con.psd.cone != "psd":
            raise InputError(f"moments are read from a scalar SOS constraint in the PSD cone; {con.name!r} "
                             f"is {con.kind!r} in cone {con.psd.cone!r}. Try: add_sos or add_nonneg_on "
                             "with cone='psd'")
        if self.program.objective is None:
            raise InputError(f"program {self.program.name!r} has no objective, so the dual of {con.name!r} is "
                             "zero: it carries no moments. Try: maximise a bound (gamma with p - gamma SOS)")
        duals = self.info.get("psd_duals")
        if duals is None:
            raise InputError(f"the {self.solver} solve returned no duals. Try: backend='direct' (Clarabel) "
                             "or a cvxpy solver that reports duals")
        first = positions(self.data.ids, con.psd.ids[:1])[0]
        k = next(k for k, (pos, _) in enumerate(self.data.psd) if pos[0] == first)
        return moments_from_dual(con.basis.vars, con.basis.exps, duals[k], tol)

    def minimizers(self, con, rank_tol: float = 1e-6, tol: float = 1e-6) -> Atoms:
        """Points where the bound of ``con`` is attained, with weights (flat extension; :mod:`.moments`).

        Each point is checked: every constraint of ``add_nonneg_on`` holds (g_i >= 0, h_j = 0) to
        ``tol`` relative to the largest coefficient, and ``con.source`` (p - gamma at the solution)
        vanishes there to within the bound's own error at that point, (|lambda_min(Q)| + N r)
        |z(x)|^2 + 1e-9 (1 + max |p_a|) (r the block's coefficient residual, N its size): a
        local minimiser above the bound by more is refused. Raises NoAtomsError when the moments
        are not flat or a point fails.
        """
        shift = max([1] + [(m.constraint.degree + 1) // 2 for m in con.multipliers])
        atoms = self.moments(con, tol).atoms(rank_tol, tol, shift)
        residual = self.value(con.source)
        residual = residual if isinstance(residual, Polynomial) else Polynomial.constant(residual)
        check_atoms(atoms, residual, [m.constraint for m in con.multipliers],
                    [m.constraint for m in con.eq_multipliers], tol, self._bound_error_at(con, residual))
        return atoms

    def _bound_error_at(self, con, residual):
        """points -> the error of the bound of ``con`` there (see ``minimizers``)."""
        c = next((c for c in self.verify().checks if c.name == con.name), None)
        if c is None:
            raise InputError(f"{con.name!r} is not a constraint of program {self.program.name!r}. "
                             "Try: the handle returned by this program's add_sos/add_nonneg_on")
        err = abs(c.min_eig) + c.basis_size * c.residual
        square = Polynomial(con.basis.vars, 2 * con.basis.exps, np.ones(len(con.basis)))
        floor = 1e-9 * (1.0 + float(np.abs(residual.coef[:, 0]).max(initial=0.0)))
        return lambda points, vars: err * square(points, vars) + floor

    def sos_decomposition(self, con, digits: int = 6) -> SOSDecomposition:
        """z^T Q z as sum_k d_k (q_k(x))^2 from the verified Gram matrix Q of ``con`` (a constraint
        or a multiplier of ``add_nonneg_on``; :mod:`.decomposition`)."""
        return sos_decomposition(con.basis.vars, con.basis.exps, self.gram_matrix(con), digits)

    @property
    def bound(self) -> Bound:
        """The rigorous bound (``rigorous_bound()``)."""
        return self.rigorous_bound()

    # ------------------------------------------------------------------ certificates
    def verify(self, eig_tol: float = 1e-7, rel_tol: float = 1e-6) -> VerificationReport:
        """Independent numerical check of every block of the certificate (:mod:`.verification`).

        Linear rows are allowed 10 x ``rel_tol`` relative to each row's scale. The report at
        the default tolerances is computed once (``SOSProgram.solve`` asks for it at once).
        """
        if self._report is not None and (eig_tol, rel_tol) == _DEFAULT_TOLS:
            return self._report
        self._require_unchanged("verify")
        t0 = time.perf_counter()
        report = verify_certificate(self.program, self.data.ids, self.x, eig_tol, rel_tol)
        if report.needs_exact and self.status in ANSWERED:
            report = self._proven(report)
        if (eig_tol, rel_tol) == _DEFAULT_TOLS:
            self._report = report
            self.timings["verify"] = time.perf_counter() - t0
        return report

    def _proven(self, report: VerificationReport) -> VerificationReport:
        """A feasibility certificate whose blocks lack a floating-point margin (p SOS but on the
        boundary, e.g. with real zeros) passes only if proven exactly (:mod:`.rigorous`)."""
        try:
            bound = self._quick_proof()
        except UnverifiedSolutionError:
            return report
        return report if bound is None else report.proven_exactly(bound.method)

    def _quick_proof(self) -> Bound | None:
        """The exact proof (:func:`~.rigorous.prove_bound`) with a short tightening schedule, kept
        as the rigorous bound when it succeeds; None inside another proof (no nested proofs).
        ``rigorous=True`` tries the full schedule."""
        global _PROVING
        if self._bound is not None or _PROVING:
            return self._bound
        _PROVING = True
        try:
            self._bound = prove_bound(self.program, self.data, self.x, QUICK_TIGHTENINGS)
        finally:
            _PROVING = False
        return self._bound

    def _require_unchanged(self, what: str):
        if self.program_version != getattr(self.program, "version", None):
            raise InputError(f"{what}: program {self.program.name!r} changed after this solve "
                             "(update, set_weights or a new constraint), so its certificate cannot "
                             "be re-checked against it. Try: prog.solve() again.")

    def rigorous_bound(self) -> Bound:
        """The objective value proven exactly (:mod:`.rigorous`); cached.

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
            self._require_unchanged("rigorous_bound")
            self._bound = prove_bound(self.program, self.data, self.x)
        except UnverifiedSolutionError as exc:
            self._bound_error = exc
            raise
        finally:
            self.timings["rigorous"] = time.perf_counter() - t0
        return self._bound

    def __repr__(self) -> str:
        t = ", ".join(f"{k} {v * 1e3:.1f} ms" for k, v in self.timings.items())
        try:
            outcome = self.outcome
        except InputError:                  # the program changed before any check was made
            outcome = "unchecked"
        return (f"Solution(status={self.status!r}, outcome={outcome!r}, solver={self.solver}, "
                f"backend={self.backend}, {t})")

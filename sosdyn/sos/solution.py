"""Solutions of SOS programs: status, values and Gram matrices -- only where proven.

The rule: no number leaves a Solution (``value``, ``objective``, ``gram_matrix``) unless the
solver's answer passes the independent check ``verify()`` (:mod:`.verification`) *and* a
point is found where every constraint is proven (:mod:`.proof`, the remedies of :mod:`.proven`):
every number is read there, so a value is one at which the constraints hold and an objective is
on the safe side of the optimum, however the program is written. In rigorous mode
(``SOSProgram.solve(rigorous=True)``) every number is read where the certificate is proven in
exact arithmetic (:mod:`.rigorous`).

A Solution refers to the program it solved, which it never changes; a program changed later
(``update``, ``set_weights``, a new constraint: its ``version`` moved on) cannot be re-checked
against this solution. ``SOSProgram.solve`` checks it at once, so the accessors of an older
solution keep working.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import (InfeasibleError, InputError, SolverError, UnboundedError,
                      UnverifiedSolutionError)
from ..poly import PolyMatrix, Polynomial
from .conic import assign_at, cvxpy_block_vars, objective_value, positions
from .decomposition import SOSDecomposition, sos_decomposition
from .gram import svec_to_matrix
from .moments import Atoms, Moments, check_atoms, moments_from_dual
from .objective import QuadraticForm, is_cvxpy
from .identity import gam
from .eigen import down
from .proven import Pending, Proof, certified, cheap_proof, exact_bound, full_proof, refusal, unverified_hint
from .rigorous import ANSWERED, Bound
from .verification import VerificationReport, verify_certificate

_HINTS = {
    "unbounded": "bound the objective (add constraints) or check its sign (maximize vs minimize)",
    "solver_error": "keep scale=True, rescale the data (coefficients of very different "
                    "magnitudes), lower the degree, or backend='cvxpy' with another installed solver",
}
_DEFAULT_TOLS = (1e-7, 1e-6)      # verify()'s default (eig_tol, rel_tol): the cached report


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


def safe_objective(data, x) -> float:
    """The affine or quadratic objective at x in the user's sense, rounded outwards by the bound of
    its own rounding (gamma_(n+4) times the sum of |terms|): <= the true value at x for a maximum,
    >= for a minimum. A single term with coefficient +-1 is exact."""
    value = objective_value(data, x)
    terms = np.abs(data.q * x)
    mag = float(terms.sum()) + abs(data.c)
    if data.P is not None:
        mag += float(np.abs(x) @ (abs(data.P) @ np.abs(x)))
    exact = data.P is None and np.count_nonzero(data.q * x) + (data.c != 0) <= 1 and \
        np.all(np.isin(np.abs(data.q[data.q != 0]), (1.0,)))
    if exact:
        return value
    err = float(gam(2 * x.size + 8)) * mag
    return down(value - err) if data.sense == "max" else -down(-(value + err))


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
        self._proof = None             # the Proof, or the UnverifiedSolutionError of its search
        self._certified = None         # the point handed out (proven, with its certificates)

    # ------------------------------------------------------------------ status
    @property
    def usable(self) -> bool:
        """The solver gave an answer and it passes ``verify()``: its numbers (``values_of``) are an
        approximate solution, good for an iterative method; nothing is proven about them."""
        return self.status in ANSWERED and self.verify().passed

    @property
    def verified(self) -> bool:
        """A point is found where every constraint is proven (``proof``): the numbers ``value``,
        ``objective`` and ``gram_matrix`` hand out are read there."""
        return self.status in ANSWERED and not isinstance(self._proven(), UnverifiedSolutionError)

    @property
    def outcome(self) -> str:
        """"verified", "unverified" (an answer not proven at any point found) or the failure status."""
        if self.status not in ANSWERED:
            return self.status
        return "verified" if self.verified else "unverified"

    def raise_for_status(self) -> "Solution":
        """Raise a typed error, with what to try, unless the answer is ``usable`` (or, failing the
        check, proven at a point the cheap remedies reach: :mod:`.proven`).

        In rigorous mode the bound must also be proven (see ``rigorous_bound``). The accessors of
        numbers also need the proof (``proof``) and raise UnverifiedSolutionError without one.
        """
        self._raise_unless_usable()
        if self.rigorous:
            self.rigorous_bound()
        return self

    def _raise_unless_usable(self):
        if self.usable:
            return
        found = self._proven() if self.status in ANSWERED else None
        if self.status in ANSWERED and not isinstance(found, UnverifiedSolutionError):
            return
        detail = f" ({self.reason})" if self.reason else f" (solver said {self.raw_status!r})"
        if self.status == "infeasible":
            raise InfeasibleError(f"program {self.program.name!r} is infeasible{detail}.",
                                  "infeasible", infeasible_hint(self.program))
        if self.status == "unbounded":
            raise UnboundedError(f"program {self.program.name!r} is unbounded: the objective has no finite "
                                 f"optimum{detail}.", "unbounded", _HINTS["unbounded"])
        if isinstance(found, UnverifiedSolutionError):
            raise found
        if self.status in ANSWERED:
            report = self.verify()
            raise UnverifiedSolutionError(
                f"the {self.solver} answer to {self.program.name!r} (solver status {self.status}) "
                f"fails the independent check, so no number from it is returned: "
                f"{report.summary()}.\n{report}", "unverified", unverified_hint(self.solver), report)
        raise SolverError(f"solving {self.program.name!r} failed: status {self.status}{detail}.",
                          self.status, _HINTS.get(self.status))

    @property
    def proof(self) -> Proof:
        """The proven point every number is read at (:mod:`.proven`), found on first use; raises
        the typed error of the status or check, or UnverifiedSolutionError saying what was tried."""
        self._raise_unless_usable()
        found = self._proven()
        if isinstance(found, UnverifiedSolutionError):
            raise found
        return found

    def settle(self) -> "Solution":
        """Run the remedies without a re-solve now (``SOSProgram.solve`` calls it while the program is
        the one solved, so an older solution keeps its numbers after the program changes)."""
        if self._proof is None and self.status in ANSWERED:
            t0 = time.perf_counter()
            self._proof = cheap_proof(self)
            self.timings["proof"] = time.perf_counter() - t0
        return self

    def _proven(self):
        """The Proof, or the UnverifiedSolutionError of its search (cached): every remedy for an
        answer that passes ``verify()``, only those without a re-solve for one that fails it."""
        self.settle()
        if isinstance(self._proof, Pending):
            if not self.usable:
                self._proof = refusal(self, self._proof)
                return self._proof
            self._require_unchanged("proof")
            t0 = time.perf_counter()
            try:
                self._proof = full_proof(self, self._proof)
            except UnverifiedSolutionError as exc:
                exc.report = self.verify()
                self._proof = exc
            finally:
                self.timings["proof"] = self.timings.get("proof", 0.0) + time.perf_counter() - t0
        return self._proof

    # ------------------------------------------------------------------ values
    def values_of(self, ids) -> np.ndarray:
        """Values of decision ids as the solver returned them (unchecked: for diagnostics)."""
        return self.x[positions(self.data.ids, np.asarray(ids, dtype=np.int64))]

    def _point(self) -> np.ndarray:
        """The decision vector handed out: the proven one (exactly proven in rigorous mode), its
        blocks the certificates proven there (:func:`~.proven.certified`; read once, while the
        program is the one solved, else the proven point as it is)."""
        if self.rigorous:
            return self.rigorous_bound().x
        proof = self.proof
        if self._certified is None:
            unchanged = self.program_version == getattr(self.program, "version", None)
            self._certified = certified(self.program, self.data.ids, proof) if unchanged else proof.x
        return self._certified

    def _assign(self, p: Polynomial) -> Polynomial:
        return assign_at(p, self.data.ids, self._point())

    def value(self, item):
        """Numbers for a decision expression: float, numeric Polynomial, ndarray or PolyMatrix,
        read at the proven point (``proof``): every constraint holds there, whatever the solver's
        own numbers (``values_of``). Raises InfeasibleError / UnverifiedSolutionError / SolverError
        when there is no such point."""
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
            return item.value(self._point()[positions(self.data.ids, item.ids)])
        if is_cvxpy(item):
            return self._cvxpy_value(item)
        raise TypeError(f"cannot take the value of {type(item).__name__}")

    def _cvxpy_value(self, expr) -> float:
        """A cvxpy expression of this program's variables at the proven point."""
        x = self._point()
        for b, var in zip(self.program.blocks, cvxpy_block_vars(self.program)):
            var.value = x[positions(self.data.ids, b.ids)]
        return expr.value

    def gram_matrix(self, item, checked: bool = True) -> np.ndarray:
        """The Gram matrix of a constraint or multiplier (anything with a ``psd`` block), at the
        proven point (the residual of its identity is what the proof absorbs).

        Raises unless verified; ``checked=False`` returns the solver's numbers anyway
        (diagnostics only).
        """
        if checked:
            self.raise_for_status()
        x = self._point() if checked else self.x
        return svec_to_matrix(x[positions(self.data.ids, item.psd.ids)], item.psd.size)

    @property
    def objective(self) -> float:
        """Objective value in the user's sense (maximise -> the maximum), at the proven point: a
        feasible point, so it is on the safe side of the optimum (<= the maximum, >= the minimum),
        rounded outwards; for a lower-bound program (maximize gamma, f - gamma SOS or >= 0 on K)
        it is a lower bound of f. In rigorous mode the exactly proven bound; ``solver_objective``
        is the solver's number."""
        self.raise_for_status()
        sense, expr = self.program.objective or ("min", None)
        if self.rigorous and self.rigorous_bound().proven is not None:
            return self.rigorous_bound().proven
        if is_cvxpy(expr):
            return float(self._cvxpy_value(expr))
        if self.proof.exact is not None and self.proof.exact.proven is not None:
            return self.proof.exact.proven
        return safe_objective(self.data, self.proof.x)

    @property
    def solver_objective(self) -> float:
        """The objective as the solver returned it (not proven: for comparison)."""
        self._raise_unless_usable()
        if is_cvxpy((self.program.objective or (None, None))[1]):
            return float(self.info.get("objective"))
        return objective_value(self.data, self.x)

    # ------------------------------------------------------------------ dual side
    def _constraint(self, con, what: str):
        """``con`` if it is an SOS constraint of this program; InputError otherwise (a multiplier,
        a constraint of another program)."""
        if not any(con is c for c in self.program.sos_constraints):
            kind = type(con).__name__
            raise InputError(f"{what} takes a constraint of program {self.program.name!r} (the handle add_sos "
                             f"or add_nonneg_on returned), got {kind} {getattr(con, 'name', con)!r}. Try: "
                             + ("the constraint the multiplier belongs to (its moments carry the points)"
                                if kind in ("Multiplier", "EqualityMultiplier") else
                                "the handle returned by this program's add_sos/add_nonneg_on"))
        return con

    def moments(self, con, tol: float = 1e-6) -> Moments:
        """The moments of an SOS constraint (the dual of its Gram block; :mod:`.moments`).

        Raises unless the solver's answer is usable, and UnverifiedSolutionError unless the dual
        is a PSD moment matrix to ``tol``.
        """
        self._raise_unless_usable()
        self._constraint(con, "moments()")
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
        ``tol`` relative to the largest coefficient, and ``con.source`` at the *solver's* numbers
        (f - gamma*: the relaxation's own value) vanishes there to within the verifier's error of
        that identity at the point, (|lambda_min(Q)| + N r) |z(x)|^2 + 1e-9 (1 + max |p_a|) (r the
        block's coefficient residual, N its size): a local minimiser above the relaxation's value by
        more is refused, a true minimiser of a flat relaxation never. The atoms carry the
        solver's value and, beside it, the proven safe bound when there is one (``Atoms.bound``).
        Raises NoAtomsError when the moments are not flat or a point fails.
        """
        self._constraint(con, "minimizers()")
        shift = max([1] + [(m.constraint.degree + 1) // 2 for m in con.multipliers])
        atoms = self.moments(con, tol).atoms(rank_tol, tol, shift)
        residual = assign_at(con.source, self.data.ids, self.x)
        check_atoms(atoms, residual, [m.constraint for m in con.multipliers],
                    [m.constraint for m in con.eq_multipliers], tol, self._bound_error_at(con, residual))
        atoms.solver_value = self.solver_objective
        try:
            atoms.bound = self.objective
        except UnverifiedSolutionError:
            pass
        return atoms

    def _bound_error_at(self, con, residual):
        """points -> the error of the identity of ``con`` there (see ``minimizers``)."""
        c = next(c for c in self.verify().checks if c.name == con.name)
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
        if (eig_tol, rel_tol) == _DEFAULT_TOLS:
            self._report = report
            self.timings["verify"] = time.perf_counter() - t0
        return report

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
        self._raise_unless_usable()
        t0 = time.perf_counter()
        try:
            self._require_unchanged("rigorous_bound")
            self._bound = exact_bound(self)
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

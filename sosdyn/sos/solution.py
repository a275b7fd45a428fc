"""Solutions of SOS programs and the independent check of their certificates.

``Solution.verify()`` does not reuse the coefficient-matching matrix the solver saw: it
rebuilds z^T Q z from the basis by polynomial arithmetic and compares it with the
constraint's polynomial at the solution. With e = p - z^T Q z and every monomial of e in
the Gram monomial set, p = z^T (Q + E) z with ||E||_2 <= sqrt(2) ||e||_2, so
lambda_min(Q) >= sqrt(2) ||e||_2 proves p SOS (up to floating point) -- ``strict``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InfeasibleError, SolverError
from ..poly import PolyMatrix, Polynomial
from ..poly.monomials import match_rows
from .gram import svec_to_matrix
from .objective import QuadraticForm, is_cvxpy

_HINTS = {
    "infeasible": "a higher degree (richer Gram basis / multipliers), a smaller decay rate gamma, "
                  "or check that the statement is true",
    "unbounded": "bound the objective (add constraints) or check its sign (maximize vs minimize)",
    "solver_error": "solver='SCS' or backend='cvxpy', keep scale=True, or lower the degree",
    "optimal_inaccurate": "solver='SCS', tighter tolerances, or a problem with more margin "
                          "(smaller gamma, lower degree)",
}


@dataclass
class CertificateCheck:
    """Numbers that say whether one SOS constraint's certificate holds."""

    name: str
    kind: str
    basis_size: int
    min_eig: float
    residual: float          # max |coefficient| of p - z^T Q z
    rel_residual: float      # residual / max |coefficient of p|
    strict: bool             # lambda_min(Q) >= sqrt2 ||e||_2 with e representable
    passed: bool


@dataclass
class VerificationReport:
    """Independent check of every certificate of a solution (see module docstring)."""

    checks: list
    linear_residual: float
    passed: bool

    @property
    def min_eig(self) -> float:
        return min((c.min_eig for c in self.checks), default=np.inf)

    @property
    def max_residual(self) -> float:
        return max((c.residual for c in self.checks), default=0.0)

    def as_dict(self) -> dict:
        return {"passed": self.passed, "min_eig": self.min_eig, "max_residual": self.max_residual,
                "linear_residual": self.linear_residual, "checks": [asdict(c) for c in self.checks]}

    def __str__(self) -> str:
        lines = [f"{'constraint':<20} {'kind':<10} {'basis':>5} {'min eig':>11} {'residual':>10} ok"]
        for c in self.checks:
            lines.append(f"{c.name:<20} {c.kind:<10} {c.basis_size:>5} {c.min_eig:>11.3e} "
                         f"{c.residual:>10.2e} {'yes' if c.passed else 'NO'}")
        lines.append(f"linear constraints residual {self.linear_residual:.2e}; "
                     f"{'PASSED' if self.passed else 'FAILED'}")
        return "\n".join(lines)


def check_gram(name, kind, p, basis_exps, Q, eig_tol=1e-7, rel_tol=1e-6) -> CertificateCheck:
    """Check p = z^T Q z, Q >= 0 for a numeric polynomial p and basis exponents (module doc)."""
    min_eig = float(np.linalg.eigvalsh(Q).min()) if Q.size else 0.0
    B = basis_exps
    zQz = Polynomial(p.vars, (B[:, None, :] + B[None, :, :]).reshape(-1, B.shape[1]), Q.ravel())
    e = p - zQz
    scale = max(1.0, float(np.abs(p.coef).max(initial=0.0)))
    res = float(np.abs(e.coef).max(initial=0.0))
    representable = bool((match_rows(zQz.exps, e.exps) >= 0).all()) if e.nterms else True
    strict = representable and min_eig >= np.sqrt(2.0) * float(np.linalg.norm(e.coef))
    passed = min_eig >= -eig_tol * max(1.0, float(np.abs(Q).max(initial=0.0))) and res <= rel_tol * scale
    return CertificateCheck(name, kind, B.shape[0], min_eig, res, res / scale, bool(strict), bool(passed))


class Solution:
    """The outcome of ``SOSProgram.solve``: status, values, certificates, timings."""

    def __init__(self, program, data, status, x, solver, backend, timings, raw_status="", info=None,
                 reason=None):
        self.program, self.data = program, data
        self.status, self.x = status, x
        self.solver, self.backend = solver, backend
        self.timings = timings
        self.raw_status, self.info, self.reason = raw_status, info or {}, reason
        self._report = None

    # ------------------------------------------------------------------ status
    @property
    def usable(self) -> bool:
        """Optimal, or inaccurate but with certificates that pass the independent check."""
        if self.status == "optimal":
            return True
        return self.status == "optimal_inaccurate" and self.verify().passed

    def raise_for_status(self) -> "Solution":
        """Raise a typed error, with what to try, unless the solution is usable."""
        if self.usable:
            return self
        detail = f" ({self.reason})" if self.reason else f" (solver said {self.raw_status!r})"
        if self.status == "infeasible":
            raise InfeasibleError(f"program {self.program.name!r} is infeasible{detail}.",
                                  "infeasible", _HINTS["infeasible"])
        if self.status == "optimal_inaccurate":
            raise SolverError(f"the {self.solver} answer to {self.program.name!r} is inaccurate and its "
                              f"certificate fails the independent check:\n{self.verify()}",
                              self.status, _HINTS[self.status])
        raise SolverError(f"solving {self.program.name!r} failed: status {self.status}{detail}.",
                          self.status, _HINTS.get(self.status))

    # ------------------------------------------------------------------ values
    def values_of(self, ids) -> np.ndarray:
        """Values of decision ids (no status check: for diagnostics)."""
        from .conic import positions
        return self.x[positions(self.data.ids, np.asarray(ids, dtype=np.int64))]

    def _assign(self, p: Polynomial) -> Polynomial:
        return p.assign(p.dec, self.values_of(p.dec)) if p.dec.size else p

    def value(self, item):
        """Numbers for a decision expression: float, numeric Polynomial, ndarray or PolyMatrix.

        Raises InfeasibleError / SolverError when the solution is not usable.
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
            return item.value(self.values_of(item.dec))
        if is_cvxpy(item):
            return item.value
        raise TypeError(f"cannot take the value of {type(item).__name__}")

    @property
    def objective(self) -> float:
        """Objective value in the user's sense (maximise -> the maximum)."""
        self.raise_for_status()
        sense, expr = self.program.objective or ("min", None)
        if is_cvxpy(expr):
            return float(self.info.get("objective"))
        d = self.data
        val = self.x @ d.q + d.c + (self.x @ (d.P @ self.x) if d.P is not None else 0.0)
        return -val if sense == "max" else val

    # ------------------------------------------------------------------ certificates
    def verify(self, eig_tol: float = 1e-7, rel_tol: float = 1e-6) -> VerificationReport:
        """Independent numerical check of every SOS certificate and linear constraint."""
        if self._report is not None:
            return self._report
        checks = []
        if not np.all(np.isfinite(self.x)):
            self._report = VerificationReport([], np.inf, False)
            return self._report
        for con in self.program.sos_constraints:
            Q = svec_to_matrix(self.values_of(con.psd.ids), con.psd.size)
            p = self._assign(con.poly.with_vars(con.basis.vars))
            checks.append(check_gram(con.name, con.kind, p, con.basis.exps, Q, eig_tol, rel_tol))
        lin = 0.0
        d = self.data
        if d.A_eq.shape[0]:
            lin = float(np.abs(d.A_eq @ self.x - d.b_eq).max())
        if d.A_ge.shape[0]:
            lin = max(lin, float(np.maximum(d.b_ge - d.A_ge @ self.x, 0).max()))
        ok = all(c.passed for c in checks) and lin <= rel_tol * 10
        self._report = VerificationReport(checks, lin, bool(ok))
        return self._report

    def __repr__(self) -> str:
        t = ", ".join(f"{k} {v * 1e3:.1f} ms" for k, v in self.timings.items())
        return f"Solution(status={self.status!r}, solver={self.solver}, backend={self.backend}, {t})"

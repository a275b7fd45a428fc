"""Lower bounds of a polynomial on a basic semialgebraic set (the Lasserre/Putinar hierarchy).

    f* = min_{x in K} f(x)  >=  gamma* = max { gamma : f - gamma >= 0 on K, certified }

with the certificate of :meth:`SOSProgram.add_nonneg_on` (Putinar multipliers up to
``degree``, optionally the preorder's products; :mod:`.sets`) or, for K = R^n, f - gamma SOS.
Raising ``degree`` gives a nondecreasing sequence of bounds converging to f* when K is
compact with an Archimedean description (Lasserre 2001). The bound is the verified value,
lowered to the safe side (:mod:`.posterior`: the solver's gamma minus what its residual and
negative eigenvalues can cost where the monomials are large), so it is <= min f in floating
point; when no such correction exists (a singular certificate on an unbounded set) a quick
exact proof's bound is returned, or UnverifiedSolutionError raised; ``rigorous=True`` always
proves it exactly. :func:`minimize_on` raises (InfeasibleError, UnverifiedSolutionError, ...)
rather than return a number the independent check does not confirm.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .constraints import SOSConstraint, as_sos_polynomial
from .program import SOSProgram
from .sets import BasicSet, as_set
from .solution import Solution


@dataclass
class LowerBound:
    """A verified lower bound ``value`` <= min f on the set, with its program and certificate.

    ``value`` is ``solution.objective``: the independently checked gamma lowered by the
    posterior correction (:func:`~.posterior.safe_point`), or with ``rigorous=True`` the
    bound proven in exact arithmetic; ``solver_value`` the solver's gamma.
    """

    value: float
    solution: Solution
    constraint: SOSConstraint
    program: SOSProgram
    solver_value: float = float("nan")


def minimize_on(f, K: BasicSet | None = None, degree=None, products=False, sparsity=None, cone="psd",
                **solve) -> LowerBound:
    """max gamma such that f - gamma >= 0 on K (module docstring); ``solve``: SOSProgram.solve's
    keywords (``rigorous=True`` for a bound proven in exact arithmetic)."""
    f = as_sos_polynomial(f)
    K = as_set(() if K is None else K)
    prog = SOSProgram("minimize_on")
    gamma = prog.new_var(name="gamma")
    if K.ineqs or K.eqs:
        con = prog.add_nonneg_on(f - gamma, K, degree=degree, products=products, sparsity=sparsity, cone=cone)
    elif degree is not None or products:
        raise InputError("degree= and products= shape the multipliers of a set; K has no constraints. "
                         "Try: minimize_on(f) for a global bound, or pass the set K")
    else:
        con = prog.add_sos(f - gamma, sparsity=sparsity, cone=cone)
    prog.maximize(gamma)
    sol = prog.solve(raise_on_failure=True, **solve)
    return LowerBound(float(sol.objective), sol, con, prog, sol.solver_objective)

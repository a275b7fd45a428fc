"""Solution: statuses, typed errors with hints that fit, values only when verified."""
import pytest

import sosdyn as sd
from sosdyn.poly import Polynomial
from sosdyn.sos import examples

(X,) = sd.variables("x")


def test_infeasible_is_reported_and_value_raises_typed_error():
    x, = sd.variables("x")
    prog = sd.SOSProgram()
    prog.add_sos(x**3)                         # odd degree: cannot be SOS
    assert not prog.solve().verified
    with pytest.raises(sd.InfeasibleError, match="Try"):
        prog.solve(raise_on_failure=True)


def test_hints_fit_the_situation(forged):
    prog, _ = examples.chebyshev()
    with pytest.raises(sd.UnverifiedSolutionError) as scs:
        prog.solve(solver="SCS").objective
    assert "solver='CLARABEL'" in scs.value.hint and "solver='SCS'" not in scs.value.hint
    prog2 = sd.SOSProgram()
    con = prog2.add_nonneg_on(X**2 - 0.25, ineqs=[1 - X**2], degree=2)
    clar = forged(prog2, [(con.multipliers[0].psd, [-0.25])], solver="CLARABEL")
    with pytest.raises(sd.UnverifiedSolutionError) as exc:
        clar.objective
    assert "SCS" not in exc.value.hint and "tol" in exc.value.hint
    prog3 = sd.SOSProgram()
    prog3.add_sos(X**3)
    with pytest.raises(sd.InfeasibleError) as inf:
        prog3.solve(raise_on_failure=True)
    assert "gamma" not in inf.value.hint and "degree" in inf.value.hint


def test_polynomial_values_of_a_verified_answer_are_numbers():
    prog, p = examples.chebyshev()
    sol = prog.solve()
    assert sol.verified and sol.outcome == "verified" and "verified" in repr(sol)
    assert isinstance(sol.value(p), Polynomial)

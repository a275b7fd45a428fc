"""The conic form: the conditioning rule of the data (sosdyn.sos.conic)."""
import pytest

import sosdyn as sd

x, y = sd.variables("x y")


# ---------------------------------------------------------------- conditioning of the data
@pytest.mark.parametrize("make", [
    lambda g: 1e100 * x**4 + 1 - g,          # was reported infeasible
    lambda g: x**4 + 3e9 * x**2 + 1 - g,     # was reported infeasible (answer: g = 1)
    lambda g: 1e12 * x**4 + 1 - g,           # was reported optimal with g = -15.7
])
def test_badly_scaled_programs_raise_instead_of_a_wrong_status(no_solver, make):
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(make(g), name="scaled")
    prog.maximize(g)
    with pytest.raises(sd.InputError, match=r"'scaled'.*above 1e\+08.*Try: rescale the variables"):
        prog.solve()


def test_moderately_scaled_programs_still_solve():
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(1e6 * (x**4 + 1) - g)
    prog.maximize(g)
    sol = prog.solve()
    assert sol.verified and sol.value(g) == pytest.approx(1e6, rel=1e-6)
    assert prog.compile().rhs_ratio == pytest.approx(1e6)

"""SOS program API: cvxpy interop, matrix variables, bad inputs; solving leaves it unchanged."""
import cvxpy as cp
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix


def test_cvxpy_constraints_and_objectives_interoperate():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    a = prog.new_var()
    b = prog.new_var()
    prog.add_sos(a * x**2 + b * y**2 - x * y)          # needs 4ab >= 1
    prog.add_constraint(prog.expr(a) <= 2)
    prog.minimize(cp.square(prog.expr(a) - 1) + cp.square(prog.expr(b) - 0.1))
    sol = prog.solve()
    assert sol.backend == "cvxpy" and sol.verified
    av, bv = sol.value(a), sol.value(b)
    assert 4 * av * bv >= 1 - 1e-5
    assert av <= 2 + 1e-6


def test_psd_matrix_variable_lmi_lyapunov():
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    prog = sd.SOSProgram()
    P = prog.new_psd(2)
    prog.add_eq(P[0, 0] + P[1, 1], 2.0)
    prog.add_sos_matrix(-(A.T @ P + P @ A) - 0.1 * PolyMatrix.identity(2))
    sol = prog.solve()
    Pv = sol.value(P)
    assert np.linalg.eigvalsh(Pv).min() > 0
    assert np.linalg.eigvalsh(A.T @ Pv + Pv @ A).max() <= -0.1 + 1e-6


def test_bad_program_inputs():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    with pytest.raises(sd.InputError, match="unknown solver"):
        prog.solve(solver="NOPE")
    with pytest.raises(sd.NotSymmetricError):
        prog.add_sos_matrix(PolyMatrix([[x, y], [1.0, x]]))
    with pytest.raises(sd.PolynomialError, match="must not depend on x"):
        prog.maximize(x)
    with pytest.raises(sd.PolynomialError, match="even degree"):
        prog.new_sos([x], 3)
    other = sd.SOSProgram().new_var()
    prog.add_sos(x**2 + other)
    with pytest.raises(sd.PolynomialError, match="another SOSProgram"):
        prog.solve()
    with pytest.raises(sd.InputError, match="cvxpy constraint"):
        sd.SOSProgram().add_constraint("x >= 0")
    with pytest.raises(sd.InputError, match="Clarabel setting"):
        p2 = sd.SOSProgram(); p2.add_sos(x**2); p2.solve(not_a_setting=1)


def test_solving_leaves_the_program_unchanged():
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(x**4 - 3 * x**2 + 2 - g)
    prog.maximize(g)
    state = lambda: (prog.version, len(prog.blocks), len(prog.linear), len(prog.sos_constraints))  # noqa: E731
    before = state()
    first = prog.solve(rigorous=True)          # a rigorous bound may re-solve a tightened copy, not prog
    second = prog.solve()
    assert state() == before and not hasattr(prog, "solution")
    assert first.program is prog and second.program is prog
    assert first.value(g) == pytest.approx(-0.25, abs=1e-6) and first.value(g) <= -0.25
    assert second.value(g) == pytest.approx(-0.25, abs=1e-7)
    assert first.verify(rel_tol=1e-9).passed    # re-checkable: the program is still the one solved

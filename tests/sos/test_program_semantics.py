"""Program-level semantics: any list of monomials as a basis; helper names never collide."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix
from sosdyn.sos.constraints import helper_names, matrix_form


def test_basis_accepts_numbers_and_monomials():
    # known answer 11: max g with x^4 + 4 - g SOS in the basis [x^2, 1] is 4
    (x,) = sd.variables("x")
    # (also with the single monomial x^2: the constant 4 - g must then vanish)
    for basis, size in [([x**2, 1], 2), ([x**2, 1.0], 2), ([3 * x**2, sd.Polynomial.constant(2.0)], 2),
                        (x**2, 1), (np.array([x**2, 1], dtype=object), 2), (np.array([[2], [0]]), 2)]:
        prog = sd.SOSProgram()
        g = prog.new_var()
        con = prog.add_sos(x**4 + 4 - g, basis=basis)
        prog.maximize(g)
        assert prog.solve().value(g) == pytest.approx(4.0, abs=1e-6)
        assert len(con.basis) == size


def test_basis_with_a_variable_not_in_the_polynomial():
    # p = x^2 in the basis [x, y]: the Gram matrix is [[1, 0], [0, 0]]
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    con = prog.add_sos(x**2, basis=[x, y])
    sol = prog.solve()
    assert con.basis.vars == ("x", "y")
    np.testing.assert_allclose(sol.gram_matrix(con), [[1, 0], [0, 0]], atol=1e-7)


def test_bad_bases_are_refused():
    (x,) = sd.variables("x")
    for bad, match in [([x + 1], "list of monomials"), ([0, x], "list of monomials"),
                       (["x"], "list of monomials"), ([x, 2 * x], "repeated"), ([True], "list of monomials")]:
        with pytest.raises(sd.PolynomialError, match=match):
            sd.SOSProgram().add_sos(x**2 + 1, basis=bad)


def test_helper_names_never_collide_with_user_variables():
    assert helper_names(2, ("x",)) == ("_y0", "_y1")
    assert helper_names(2, ("_y1", "x")) == ("__y0", "__y1")
    assert helper_names(1, ("_y0", "__y0")) == ("___y0",)
    # a user variable called _y0: max t with [[_y0^2 + 1 - t, 0], [0, 1 - t]] an SOS matrix is 1
    (u,) = sd.variables("_y0")
    prog = sd.SOSProgram()
    t = prog.new_var()
    P = PolyMatrix([[u**2 + 1 - t, 0], [0, 1 - t]])
    q, _ = matrix_form(P)
    assert "_y0" in q.vars and "__y0" in q.vars and "__y1" in q.vars
    prog.add_sos_matrix(P)
    prog.maximize(t)
    assert prog.solve().value(t) == pytest.approx(1.0, abs=1e-6)


def test_family_terms_share_helper_names():
    # terms [[_y0^2, 0], [0, 0]] and I: max t with w0 T0 + w1 T1 - t I SOS at w = (1, 2): t = 2
    (u,) = sd.variables("_y0")
    prog = sd.SOSProgram()
    t = prog.new_var()
    terms = [PolyMatrix([[u**2, 0], [0, 0]]), PolyMatrix([[1, 0], [0, 1]]),
             PolyMatrix([[-t, 0], [0, -t]])]
    prog.add_sos_matrix_family(terms, [1.0, 2.0, 1.0])
    prog.maximize(t)
    assert prog.solve().value(t) == pytest.approx(2.0, abs=1e-6)


def test_infeasible_hints_fit_the_program():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram("metric step", hint="a lower contraction rate")
    prog.add_sos(-1 - x**2)
    with pytest.raises(sd.InfeasibleError, match="a lower contraction rate"):
        prog.solve(raise_on_failure=True)
    prog = sd.SOSProgram()
    prog.add_sos(-1 - x**2 - y**2 - x * y, sparsity="term")
    with pytest.raises(sd.InfeasibleError, match="sparsity=None") as err:
        prog.solve(raise_on_failure=True)
    assert "contraction" not in str(err.value) and "decay" not in str(err.value)

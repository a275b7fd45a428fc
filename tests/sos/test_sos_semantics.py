"""SOS-level semantics (issue 15, item 6): the SOS-decomposition printer, UnboundedError, and
infeasibility hints that fit the kind of program."""
import numpy as np
import pytest
import sympy

import sosdyn as sd
from sosdyn.sos.decomposition import sos_decomposition
from sosdyn.sos.examples import disc_minimum


@pytest.fixture
def xy():
    return sd.variables("x y")


def coefficient_gap(text: str, p) -> float:
    """max |coefficient| of (the printed sum, parsed by sympy) - p."""
    printed = sympy.sympify(text.replace("^", "**"))
    diff = sympy.Poly(sympy.expand(printed - sd.to_sympy(p)), *sympy.symbols(p.vars))
    return max([abs(float(c)) for c in diff.coeffs()], default=0.0)


def test_printed_decomposition_reproduces_the_polynomial(xy):
    x, y = xy
    p = 2 * x**4 + 2 * x**3 * y - x**2 * y**2 + 5 * y**4          # known SOS (Parrilo), basis x^2, xy, y^2
    prog = sd.SOSProgram()
    con = prog.add_sos(p)
    sol = prog.solve()
    dec = sol.sos_decomposition(con)
    assert (dec.weights > 0).all() and 1 <= len(dec) <= 3
    text = str(dec)
    assert coefficient_gap(text, p) <= 1e-5                        # 6 significant digits shown
    assert (dec.polynomial() - p).coef[:, 0].max(initial=0) <= 1e-5
    coarse = sol.sos_decomposition(con, digits=2)
    assert 1e-6 < coefficient_gap(str(coarse), p) <= 0.1           # fewer digits: visibly coarser


def test_decomposition_of_an_exact_gram_matrix():
    # x^4 - x^2 + 1 = z^T Q z, z = (1, x, x^2): pivot 1 (first of the equal diagonals), then x^2
    basis = np.array([[0], [1], [2]])
    Q = np.array([[1.0, 0.0, -0.5], [0.0, 0.0, 0.0], [-0.5, 0.0, 1.0]])
    dec = sos_decomposition(("x",), basis, Q)
    assert str(dec) == "1*(1 - 0.5*x^2)^2 + 0.75*(x^2)^2"
    (x,) = sd.variables("x")
    assert dec.polynomial() == x**4 - x**2 + 1


def test_decomposition_of_a_putinar_certificate(xy):
    # x + 1 = 1/2 (1 + x)^2 + 1/2 y^2 + 1/2 (1 - x^2 - y^2): the certificate of min x = -1 on the disc
    x, y = xy
    prog, g, con = disc_minimum()
    sol = prog.solve()
    main, mult = sol.sos_decomposition(con), sol.sos_decomposition(con.multipliers[0])
    assert main.weights == pytest.approx([0.5, 0.5], abs=1e-4) and mult.weights == pytest.approx([0.5], abs=1e-4)
    total = main.polynomial() + mult.polynomial() * (1 - x**2 - y**2)
    assert total.allclose(x + 1, atol=1e-5)


def test_unbounded_program_raises_unbounded_error():
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    g = prog.new_var(name="g")
    prog.add_sos(x**2 + g)                                         # g can grow without bound
    prog.maximize(g)
    sol = prog.solve()
    with pytest.raises(sd.UnboundedError, match="unbounded") as exc:
        sol.value(g)
    assert isinstance(exc.value, sd.SolverError) and "maximize vs minimize" in exc.value.hint


def test_infeasible_hints_fit_the_program(xy):
    x, y = xy
    motzkin = x**4 * y**2 + x**2 * y**4 + 1 - 3 * x**2 * y**2
    prog = sd.SOSProgram()
    prog.add_sos(motzkin)
    with pytest.raises(sd.InfeasibleError) as plain:
        prog.solve().raise_for_status()
    hint = plain.value.hint
    assert "Motzkin" in hint and "gamma" not in hint and "multiplier" not in hint
    prog = sd.SOSProgram()
    prog.add_nonneg_on(-1 - x**2, ineqs=[1 - x**2], degree=2)      # -1 - x^2 >= 0 on [-1, 1]: false
    with pytest.raises(sd.InfeasibleError) as putinar:
        prog.solve().raise_for_status()
    assert "multiplier degree" in putinar.value.hint and "gamma" not in putinar.value.hint

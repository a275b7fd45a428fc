"""Polynomial layer: exact algebra against sympy, calculus, evaluation, decision coefficients."""
import numpy as np
import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

import sosdyn as sd
from sosdyn.poly import jacobian

X, Y, Z = sympy.symbols("x y z")
NAMES = ["x", "y", "z"]

terms = st.lists(st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 2),
                           st.integers(-5, 5)), min_size=0, max_size=6)


def build(ts):
    expr = sum((c * X**a * Y**b * Z**e for a, b, e, c in ts), sympy.Integer(0))
    return expr, sd.from_sympy(expr, NAMES)


def same(poly, expr):
    return sympy.expand(sd.to_sympy(poly) - expr) == 0


@settings(max_examples=30, deadline=None, derandomize=True)
@given(terms, terms, terms)
def test_ring_laws_match_sympy(t1, t2, t3):
    (e1, p1), (e2, p2), (e3, p3) = build(t1), build(t2), build(t3)
    assert same(p1 + p2, e1 + e2)
    assert same(p1 - p2, e1 - e2)
    assert same(p1 * p2, e1 * e2)
    assert ((p1 * p2) * p3).allclose(p1 * (p2 * p3), atol=1e-9)
    assert same(p1 * (p2 + p3), e1 * e2 + e1 * e3)
    assert same(p1**2, e1**2)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(terms)
def test_derivatives_and_evaluation_match_sympy(t):
    e, p = build(t)
    for name, s in zip(NAMES, (X, Y, Z)):
        assert same(p.diff(name), sympy.diff(e, s))
    pts = np.array([[0.5, -1.0, 2.0], [1.5, 0.25, -0.5]])
    want = [float(e.subs({X: a, Y: b, Z: c})) for a, b, c in pts]
    np.testing.assert_allclose(p(pts, NAMES), want, rtol=1e-12, atol=1e-12)


def test_directional_derivative_and_jacobian():
    x, y = sd.variables("x y")
    V = x**2 + 3 * x * y
    f = [-y, x - y**3]
    dV = V.directional_derivative(f, ["x", "y"])
    expect = sympy.expand((2 * X + 3 * Y) * (-Y) + 3 * X * (X - Y**3))
    assert same(dV, expect)
    J = jacobian(f, [x, y])
    np.testing.assert_allclose(J([[1.0, 2.0]], [x, y])[0], [[0, -1], [1, -12]])


def test_derivatives_take_variables_as_well_as_names():
    """d/dx by the variable object equals d/dx by name; a non-indeterminate is an error, never 0."""
    x, y = sd.variables("x y")
    V = x**2 * y + 3 * y
    assert same(V.diff(x), 2 * X * Y) and same(V.diff("x"), 2 * X * Y)
    assert same(V.directional_derivative([y, x], [x, y]), sympy.expand(2 * X * Y * Y + (X**2 + 3) * X))
    with pytest.raises(sd.PolynomialError, match="not an indeterminate"):
        V.diff(2 * x)


def test_substitution_with_numbers_and_polynomials():
    x, y = sd.variables("x y")
    p = x**2 * y + 2 * y
    assert same(p.subs({"x": 2 * y}), sympy.expand(4 * Y**3 + 2 * Y))
    assert p.subs({"x": 1.0, "y": 3.0}).constant_value() == pytest.approx(9.0)


def test_decision_coefficients_stay_affine_and_assign():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    a, b = prog.new_var(), prog.new_var()
    p = a * x**2 + b * y + 1
    q = x * p                              # numeric * affine is affine
    assert q.ids.size == 2 and q.degree == 3
    with pytest.raises(sd.PolynomialError, match="bilinear"):
        _ = a * b
    v = q.assign(q.ids, [2.0, -1.0])
    assert same(v, sympy.expand(X * (2 * X**2 - Y + 1)))


def test_mismatched_inputs_raise_clear_errors():
    x, y = sd.variables("x y")
    with pytest.raises(sd.PolynomialError, match="non-negative integer"):
        _ = x ** -1
    with pytest.raises(sd.PolynomialError, match="columns"):
        (x + y)(np.ones((4, 3)), ["x", "y"])
    with pytest.raises(sd.PolynomialError, match="not a polynomial"):
        sd.from_sympy(sympy.sin(X), ["x"])
    with pytest.raises(sd.PolynomialError, match="not in vars"):
        sd.from_sympy(X * Y, ["x"])
    with pytest.raises(sd.PolynomialError, match="duplicate"):
        sd.variables("x x")

"""Input guards of the polynomial layer (sosdyn.poly.checks): non-finite, complex and absurd
coefficients, overflow, absurd degrees and exponent arrays, sizes, evaluation points."""

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import MAX_COEFFICIENT, MAX_DEGREE, PolyMatrix, Polynomial

x, y = sd.variables("x y")


# ---------------------------------------------------------------- non-finite coefficients
@pytest.mark.parametrize("make, match", [
    (lambda: x**2 + float("nan"), "NaN"),
    (lambda: Polynomial(("x",), [[1]], [np.nan]), "NaN"),
    (lambda: x * np.inf, "infinite"),
    (lambda: x - np.float64(-np.inf), "infinite"),
    (lambda: PolyMatrix([[x, np.nan], [1.0, x]]), "NaN"),
    (lambda: PolyMatrix([[x, y], [y, x]]) + np.array([[0.0, np.inf], [0.0, 0.0]]), "infinite"),
    (lambda: Polynomial.affine([0], [np.nan]), "NaN"),
])
def test_nan_and_inf_coefficients_are_refused(make, match):
    with pytest.raises(sd.PolynomialError, match=match):
        make()


def test_the_reported_nan_program_never_reaches_the_solver():
    # the issue: maximise g s.t. x^2 + nan - g SOS returned "optimal", g = 1e20
    prog = sd.SOSProgram()
    g = prog.new_var()
    with pytest.raises(sd.PolynomialError, match="NaN.*Try"):
        prog.add_sos(x**2 + float("nan") - g)
    assert not prog.sos_constraints


def test_assigning_nan_decision_values_is_refused():
    prog = sd.SOSProgram()
    a = prog.new_var()
    p = a * x**2 + 1
    with pytest.raises(sd.PolynomialError, match="NaN"):
        p.assign(p.ids, [np.nan])
    assert p.assign(p.ids, [2.0]).allclose(2 * x**2 + 1)


# ---------------------------------------------------------------- complex numbers
@pytest.mark.parametrize("make", [
    lambda: x * (1 + 2j),
    lambda: x + 1j,
    lambda: (1 + 0j) - x,
    lambda: x / 2j,
    lambda: Polynomial(("x",), [[1]], np.array([1 + 1j])),
    lambda: Polynomial.constant(np.complex128(3)),
    lambda: PolyMatrix([[1j, x]]),
    lambda: np.array([[1j, 0], [0, 1]]) @ PolyMatrix([[x, y], [y, x]]),
    lambda: (x + y)(np.array([[1 + 1j, 2]]), ["x", "y"]),
    lambda: PolyMatrix([[x]])(np.array([[1j]]), [x]),
    lambda: sd.SOSProgram().new_poly([x], 2).assign([0], [1j]),
])
def test_complex_numbers_raise_a_polynomial_error_not_a_type_error(make):
    with pytest.raises(sd.PolynomialError, match="complex"):
        make()


# ---------------------------------------------------------------- magnitudes and overflow
def test_huge_coefficients_are_refused_with_a_rescaling_hint():
    with pytest.raises(sd.PolynomialError, match=r"1e\+300.*Try: rescale the variables"):
        _ = 1e300 * x**4 + 1
    with pytest.raises(sd.PolynomialError, match="above 1e\\+150"):
        Polynomial(("x",), [[4], [0]], [1e151, 1.0])
    p = MAX_COEFFICIENT * x**4 + 1                   # the bound itself is admissible
    assert p.coeff((4,)).constant_value() == 1e150


def test_the_reported_1e300_program_raises_instead_of_infeasible():
    prog = sd.SOSProgram()
    with pytest.raises(sd.PolynomialError, match="rescale"):
        prog.add_sos(1e300 * x**4 + 1)


@pytest.mark.parametrize("make", [
    lambda: (1e100 * x) * (1e100 * y),               # 1e200: finite, but over the bound
    lambda: (1e80 * x + 1) ** 2,
    lambda: (x + 1) ** 1000,                         # binomial coefficients up to 2.7e299
    lambda: Polynomial.constant(2.0) ** 2000,        # 2^2000 overflows to inf
    lambda: (1e100 * x) / 1e-100,
])
def test_arithmetic_that_overflows_raises(make):
    with pytest.raises(sd.PolynomialError, match="above 1e\\+150|infinite"):
        make()


def test_division_by_zero_is_a_polynomial_error():
    with pytest.raises(sd.PolynomialError, match="by zero"):
        _ = x / 0


# ---------------------------------------------------------------- degrees and sizes
def test_absurd_powers_raise_before_expanding(monkeypatch):
    products = []
    real = Polynomial.__mul__
    monkeypatch.setattr(Polynomial, "__mul__", lambda a, b: products.append((a, b)) or real(a, b))
    with pytest.raises(sd.PolynomialError, match="degree 1000000"):
        _ = x ** 10**6
    with pytest.raises(sd.PolynomialError, match="degree"):
        _ = (x + y + 1) ** 2**70
    assert not products                                # refused from the degree: nothing multiplied
    with pytest.raises(sd.PolynomialError, match="degree 1200"):
        _ = x**600 * y**600                            # one product of two monomials, refused
    assert (x ** MAX_DEGREE).degree == 1000            # the bound itself is admissible


def test_exponent_arrays_must_be_small_non_negative_integers():
    with pytest.raises(sd.PolynomialError, match="degree 2000"):
        Polynomial(("x",), [[2000]], [1.0])
    with pytest.raises(sd.PolynomialError, match="non-negative integers"):
        Polynomial(("x",), [[1.5]], [1.0])
    with pytest.raises(sd.PolynomialError, match="negative exponents"):
        Polynomial(("x",), [[-1]], [1.0])
    assert Polynomial(("x",), [[2.0]], [3.0]).allclose(3 * x**2)


def test_products_are_size_checked_before_they_are_expanded():
    p = sum(x**i for i in range(41))                            # 41 terms: p*p has 41 x 41 rows
    need = 16 * 41 * 41 * (1 + 1)                               # 16 bytes x rows x (1 var + 1 coef)
    with sd.limits(max_bytes=need):
        assert (p * p).nterms == 81
    with sd.limits(max_bytes=need - 1):
        with pytest.raises(sd.ResourceLimitError, match="a product.*1681 terms"):
            _ = p * p


# ---------------------------------------------------------------- evaluation points
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_evaluation_at_non_finite_points_is_refused(bad):
    with pytest.raises(sd.PolynomialError, match="NaN or inf"):
        (x * y)(np.array([[1.0, bad]]), ["x", "y"])
    with pytest.raises(sd.PolynomialError, match="NaN or inf"):
        PolyMatrix([[x, y]])(np.array([[bad, 1.0]]), [x, y])
    assert (x * y)(np.array([[2.0, 3.0]]), ["x", "y"])[0] == 6.0

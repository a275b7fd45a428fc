"""Results of polynomial operations (made by Polynomial._made without the input checks):
canonical form, and the rules an operation can break (overflow, degree) still enforced."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import PolynomialError
from sosdyn.poly import Polynomial


@pytest.fixture
def xy():
    return sd.variables("x y")


def test_cancellation_gives_the_zero_polynomial_and_drops_unused_decisions(xy):
    x, y = xy
    prog = sd.SOSProgram()
    a, b = prog.new_var(), prog.new_var()
    p = (x + a * y) - (x + a * y)
    assert p.nterms == 0 and p.ids.size == 0
    q = (a * x + b * y) - b * y
    np.testing.assert_array_equal(q.ids, a.ids)
    np.testing.assert_array_equal(q.exps, [[1, 0]])
    np.testing.assert_array_equal(q.coef, [[0.0, 1.0]])


def test_results_are_sorted_and_combined(xy):
    x, y = xy
    p = (y + x) * (x - y)
    np.testing.assert_array_equal(p.exps, [[0, 2], [2, 0]])      # x^2 - y^2, the x*y terms cancelled
    np.testing.assert_array_equal(p.coef[:, 0], [-1.0, 1.0])
    assert p == Polynomial(("x", "y"), [[2, 0], [0, 2]], [1.0, -1.0])


def test_power_of_a_monomial_and_of_a_sum(xy):
    x, y = xy
    assert (3 * x * y**2) ** 3 == Polynomial(("x", "y"), [[3, 6]], [27.0])
    assert ((x + y) ** 3).coef[:, 0].tolist() == [1.0, 3.0, 3.0, 1.0]
    assert (x + y) ** 0 == 1 and (2 * x) ** 0 == 1 and (x + y) ** 1 == x + y


@pytest.mark.parametrize("make", [
    lambda x: 1e150 * x + 1e150 * x,                 # a sum above 1e150
    lambda x: (1e150 * x) * (1e150 * x),            # a product (1e300)
    lambda x: (1e100 * x) ** 2,                     # a power of a monomial
    lambda x: (1e100 * x + 1) ** 4,                 # a power of a sum
    lambda x: (1e100 * x) * 1e100,                  # times a scalar
    lambda x: (1e149 * x**1000).diff("x"),          # d/dx multiplies by the exponent 1000
    lambda x: x * float("nan"),
    lambda x: x * float("inf"),
])
def test_overflow_in_an_operation_is_refused(xy, make):
    with pytest.raises(PolynomialError, match="coefficient"):
        make(xy[0])


def test_degree_of_a_product_is_checked(xy):
    x, y = xy
    with pytest.raises(PolynomialError, match="degree 1200"):
        (x**600 + y) * (x**600 + 1)
    assert ((x**500 + y) * (x**500 + 1)).degree == 1000


def test_underflow_drops_the_term(xy):
    x, y = xy
    p = (1e-200 * x + y) * 1e-200
    np.testing.assert_array_equal(p.exps, [[0, 1]])       # 1e-400 is 0.0 in double precision

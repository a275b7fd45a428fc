"""Monomial values and gradients (sosdyn.poly.evaluation): known numbers, and the one evaluation
every Polynomial uses."""
import numpy as np

import sosdyn as sd
from sosdyn.poly import monomial_gradients, monomial_values

EXPS = np.array([[0, 0], [1, 0], [2, 1], [0, 3]])
Z = np.array([[2.0, -1.0], [0.5, 3.0]])


def test_monomial_values_are_the_products_of_powers():
    np.testing.assert_array_equal(monomial_values(Z, EXPS), [[1, 2, -4, -1], [1, 0.5, 0.75, 27]])


def test_monomial_gradients_are_the_exact_derivatives():
    D = monomial_gradients(Z, EXPS)                          # (N, n, m): d z^e_j / d z_i
    assert D.shape == (2, 2, 4)
    # d/dz1: (0, 1, 2 z1 z2, 0); d/dz2: (0, 0, z1^2, 3 z2^2)
    np.testing.assert_array_equal(D[0], [[0, 1, -4, 0], [0, 0, 4, 3]])
    np.testing.assert_array_equal(D[1], [[0, 1, 3, 0], [0, 0, 0.25, 27]])


def test_a_polynomial_evaluates_through_monomial_values():
    x, y = sd.variables("x y")
    p = 3 * x**2 * y - y**3 + 0.5 * x + 1
    pts = np.random.default_rng(0).normal(size=(50, 2))
    np.testing.assert_array_equal(p(pts, ["x", "y"]), monomial_values(pts, p.exps) @ p.coef[:, 0])
    np.testing.assert_array_equal(p.monomial_values(pts[:, ::-1], ["y", "x"]), monomial_values(pts, p.exps))

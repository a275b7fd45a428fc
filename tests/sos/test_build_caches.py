"""Cached Newton bases and Gram matching maps: same answers, read-only, limits still enforced."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import ResourceLimitError
from sosdyn.sos import newton_basis
from sosdyn.sos.gram import SQRT2, gram_matching, svec_to_matrix


def test_newton_basis_of_the_motzkin_support_is_cached_and_read_only():
    support = np.array([[4, 2], [2, 4], [0, 0], [2, 2]])
    first, again = newton_basis(support), newton_basis(support.copy())
    np.testing.assert_array_equal(first, [[0, 0], [1, 1], [2, 1], [1, 2]])   # graded, larger x first
    assert again is first and not first.flags.writeable


def test_a_cached_basis_still_obeys_the_memory_limit():
    support = np.array([[8, 0, 0], [0, 8, 0], [0, 0, 8], [0, 0, 0]])
    assert newton_basis(support).shape[0] == 35                  # all monomials of degree <= 4
    with sd.limits(max_bytes=10_000), pytest.raises(ResourceLimitError):
        newton_basis(support)


def test_gram_matching_maps_svec_to_the_coefficients_of_the_form():
    basis = np.array([[0], [1], [2]])                           # z = (1, x, x^2)
    exps, rows, weights = gram_matching(basis)
    np.testing.assert_array_equal(exps, [[0], [1], [2], [3], [4]])
    Q = np.array([[1.0, 2.0, 3.0], [2.0, 5.0, 7.0], [3.0, 7.0, 11.0]])
    s = np.array([Q[0, 0], SQRT2 * Q[0, 1], Q[1, 1], SQRT2 * Q[0, 2], SQRT2 * Q[1, 2], Q[2, 2]])
    np.testing.assert_allclose(svec_to_matrix(s, 3), Q)
    coef = np.bincount(rows, weights * s, minlength=exps.shape[0])
    np.testing.assert_allclose(coef, [1.0, 4.0, 11.0, 14.0, 11.0])   # z^T Q z = 1 + 4x + 11x^2 + 14x^3 + 11x^4
    assert gram_matching(basis.copy())[1] is rows and not rows.flags.writeable


def test_two_programs_with_the_same_basis_solve_independently():
    x, y = sd.variables("x y")
    for scale, feasible in ((1.0, True), (-1.0, False)):
        prog = sd.SOSProgram()
        prog.add_sos(scale * (2 * x**4 + 2 * x**3 * y - x**2 * y**2 + 5 * y**4))
        assert prog.solve().verified is feasible

"""Gram bases from the Newton polytope, and the size check of coefficient matching."""
import itertools

import numpy as np
import pytest
from scipy.optimize import linprog

import sosdyn as sd
from sosdyn.sos import newton_basis
from sosdyn.sos.newton import HULL_MAX_DIM, gram_matching_bytes, in_hull, in_hull_lp

x, y = sd.variables("x y")


def test_newton_basis_of_a_homogeneous_form():
    x, y = sd.variables("x y")
    p = x**6 + y**6
    b = newton_basis(p.exps)
    assert {tuple(r) for r in b} == {(3, 0), (2, 1), (1, 2), (0, 3)}


def test_gram_matching_is_checked_before_it_allocates():
    assert gram_matching_bytes(66, 2) == 8.0 * 2211 * 16
    with sd.limits(max_bytes=int(gram_matching_bytes(66, 2)) - 1):
        with pytest.raises(sd.ResourceLimitError, match="Gram basis of 66 monomials"):
            sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10)
    assert len(sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10).basis) == 66


@pytest.mark.parametrize("n", [8, 16])
def test_newton_basis_of_chained_rosenbrock_by_hull_and_by_lp(n):
    # support: 4e_i (i <= n-2), 2e_i + e_i+1, 2e_j, e_i, 0. Degree-4 points are only the 4e_i with
    # i <= n-2, so 2a in N for |a| <= 2 exactly for 0, every e_j, 2e_i and e_i + e_k (i, k <= n-2):
    # 1 + n + (n - 1) + (n - 1)(n - 2)/2 monomials. n = 8 runs through Qhull, n = 16 through LPs.
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    f = sum(100 * (xs[i + 1] - xs[i] ** 2) ** 2 + (1 - xs[i]) ** 2 for i in range(n - 1))
    assert (n > HULL_MAX_DIM) == (n == 16)           # the support spans n dimensions
    b = newton_basis(f.exps)
    assert b.shape[0] == 1 + n + (n - 1) + (n - 1) * (n - 2) // 2
    assert not (b[:, -1] == 2).any() and b.sum(axis=1).max() == 2


def test_newton_basis_in_12_variables_is_every_half_point_of_the_hull():
    # chained Rosenbrock in 12 variables: a support Qhull cannot start on (a flat initial simplex);
    # the basis must be exactly the monomials a, |a| <= 2, with 2a a convex combination of the
    # support's exponents, each decided here by its own LP (lambda >= 0, sum 1, S^T lambda = 2a)
    n = 12
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    f = sum(100 * (xs[i + 1] - xs[i] ** 2) ** 2 + (1 - xs[i]) ** 2 for i in range(n - 1))
    S = f.exps.astype(float)
    A = np.vstack([S.T, np.ones(len(S))])
    cands = [np.bincount(c, minlength=n) for d in range(3)
             for c in itertools.combinations_with_replacement(range(n), d)]
    half = {tuple(int(v) for v in a) for a in cands
            if linprog(np.zeros(len(S)), A_eq=A, b_eq=np.append(2.0 * a, 1.0), bounds=(0, None)).status == 0}
    assert {tuple(int(v) for v in r) for r in newton_basis(f.exps)} == half
    assert len(half) == 1 + n + (n - 1) + (n - 1) * (n - 2) // 2      # the closed form above


def test_hull_membership_by_lp_agrees_with_qhull():
    rng = np.random.default_rng(0)
    support = rng.integers(0, 5, size=(12, 4))
    points = rng.integers(0, 5, size=(200, 4))
    inside = in_hull(points, support)
    assert 0 < inside.sum() < 200
    np.testing.assert_array_equal(in_hull_lp(points, support), inside)

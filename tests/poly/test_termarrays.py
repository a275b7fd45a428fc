"""Term arrays (sosdyn.poly.termarrays) and the PolyMatrix operations built on them: the same
canonical Polynomials as entry-by-entry arithmetic, and known answers."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix, Polynomial, allocate
from sosdyn.poly.termarrays import (matrix_terms, terms_directional_derivative, terms_entries, terms_jacobian,
                                    terms_matmul, terms_transpose)

VARS = ("x", "y")


def _same(a, b, tol=1e-13):
    """Entry by entry: the same monomials in the same order, the same ids, coefficients to tol."""
    a = a.entries if isinstance(a, PolyMatrix) else a
    b = b.entries if isinstance(b, PolyMatrix) else b
    assert a.shape == b.shape
    for (i, j), p in np.ndenumerate(a):
        q = b[i, j]
        assert np.array_equal(p.exps, q.exps) and np.array_equal(p.ids, q.ids), (i, j)
        np.testing.assert_allclose(q.coef, p.coef, rtol=0, atol=tol)


def _matrices():
    x, y = sd.variables("x y")
    d = allocate(3)
    a = Polynomial.affine(d[:1], [2.0], vars=VARS) * (x * y) + Polynomial.affine(d[1:], [1.0, -1.0], vars=VARS)
    A = PolyMatrix([[1 + x**2, x * y], [3.0 + 0 * x, y**3 - x]])
    B = PolyMatrix([[a, 0.0 * x], [x - 2 * y, a * 0.5 + x]])
    return x, y, a, A, B


def test_products_and_derivatives_match_entrywise_arithmetic():
    x, y, a, A, B = _matrices()
    AB = terms_entries(terms_matmul(matrix_terms(A.entries, VARS), matrix_terms(B.entries, VARS)), (2, 2), VARS)
    _same(A.entries @ B.entries, AB)                              # numpy's object matmul: entry by entry
    assert AB[0, 1].allclose(x * y * (a * 0.5 + x), 1e-15)        # known answer
    AtB = terms_matmul(terms_transpose(matrix_terms(A.entries, VARS)), matrix_terms(B.entries, VARS))
    _same(A.entries.T @ B.entries, terms_entries(AtB, (2, 2), VARS))
    f = [x**2 * y - y, 2 * x + y**3]
    J = terms_entries(terms_jacobian(matrix_terms(f, VARS), 2), (2, 2), VARS)
    assert J[1, 1].allclose(3 * y**2) and J[0, 0].allclose(2 * x * y) and J[0, 1].allclose(x**2 - 1)
    dB = terms_directional_derivative(matrix_terms(B.entries, VARS), matrix_terms(f, VARS), 2)
    ref = np.array([[p.directional_derivative(f, VARS) for p in row] for row in B.entries], dtype=object)
    _same(ref, terms_entries(dB, (2, 2), VARS))


def test_polymatrix_operators_on_term_arrays_equal_entrywise_results():
    x, y, a, A, B = _matrices()
    _same(A.entries @ B.entries, A @ B)
    _same(A.entries + B.entries, A + B)
    _same(np.array([[1.0, 2.0], [0.0, -1.0]]) @ A.entries, np.array([[1.0, 2.0], [0.0, -1.0]]) @ A)
    S = A + A.T
    assert S.is_symmetric() and np.all(S.asymmetry() == 0.0)
    assert A.asymmetry()[0, 1] == pytest.approx(1.0)   # x y - 3: largest difference 3, over A's largest 3


def test_symmetry_is_judged_relative_to_the_largest_coefficient():
    x, y = sd.variables("x y")
    big = 1e4 * (x**2 + y**2) + 7e3 * x * y
    roundoff = PolyMatrix([[big, big + 1e-12 * x * y], [big, big]])        # 1e-16 relative
    assert roundoff.is_symmetric() and roundoff.asymmetry()[0, 1] == pytest.approx(1e-16)
    roundoff.check_symmetric()
    wrong = PolyMatrix([[big, big + 1e-6 * x * y], [big, big]])            # 1e-10 relative
    assert not wrong.is_symmetric()
    with pytest.raises(sd.NotSymmetricError, match=r"\(0,1\) and \(1,0\)"):
        wrong.check_symmetric()
    small = PolyMatrix([[x, x + 1e-11], [x, x]])                          # scale below 1: absolute
    assert not small.is_symmetric()


def test_bilinear_products_are_refused_and_exact_cancellations_vanish():
    x, y = sd.variables("x y")
    d = allocate(2)
    a, b = Polynomial.affine(d[:1], [1.0], vars=VARS) * x, Polynomial.affine(d[1:], [1.0], vars=VARS)
    with pytest.raises(sd.PolynomialError, match="bilinear"):
        PolyMatrix([[a]]) @ PolyMatrix([[b]])
    zero = (PolyMatrix([[x, -y]]) @ PolyMatrix([[y], [x]]))[0, 0]  # x y - y x
    assert zero.nterms == 0 and zero.ids.size == 0


def test_check_symmetric_names_the_first_asymmetric_pair():
    x, y = sd.variables("x y")
    P = PolyMatrix([[x, y, 1.0 + 0 * x], [y, 1.0 + 0 * x, x], [1.0 + 0 * x, x + 1e-6, y]])
    with pytest.raises(sd.NotSymmetricError, match=r"entries \(1,2\) and \(2,1\) differ by -1e-06"):
        P.check_symmetric()
    assert P.check_symmetric(atol=1e-5) is P

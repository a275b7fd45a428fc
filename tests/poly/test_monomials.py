"""Monomial exponent arrays (sosdyn.poly.monomials): enumeration, unique and matched rows."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import match_rows, monomials_up_to, unique_rows
from sosdyn.poly.monomials import sum_rows, wide_keys


def test_monomial_enumeration_is_size_checked():
    with pytest.raises(sd.PolynomialError, match="above 1000"):
        monomials_up_to(2, 2000)
    with pytest.raises(sd.ResourceLimitError, match="monomials of degree <= 30 in 30 variables"):
        monomials_up_to(30, 30)                    # C(60, 30) = 1.2e17 rows
    assert monomials_up_to(10, 4).shape == (1001, 10)   # C(14, 4): fast now, no itertools.product


def test_unique_rows_and_match_rows_are_inverse_lookups():
    exps = np.array([[2, 0], [0, 1], [2, 0], [1, 1], [0, 1]])
    uniq, inv = unique_rows(exps)
    assert uniq.tolist() == [[0, 1], [1, 1], [2, 0]]                  # lexicographic
    np.testing.assert_array_equal(uniq[inv], exps)
    np.testing.assert_array_equal(match_rows(uniq, np.array([[1, 1], [3, 0], [2, 0]])), [1, -1, 2])
    big = np.array([[0, 10**7, 0, 10**7, 0], [1, 0, 0, 0, 0]])           # keys overflow: the tuple path
    np.testing.assert_array_equal(match_rows(big, big[::-1]), [1, 0])
    assert monomials_up_to(2, 2).tolist() == [[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2]]


def test_wide_rows_sort_and_combine_as_dense_rows():
    # 500 variables: mixed-radix keys overflow, the sparse keys order rows lexicographically
    n = 500
    rows = np.zeros((6, n), dtype=np.int64)
    rows[0, 499] = 1            # x499
    rows[1, 0] = 1              # x0
    rows[2, [0, 499]] = 1       # x0 x499
    rows[3, 0] = 2              # x0^2
    rows[4] = rows[1]           # x0 again
    keys = wide_keys(rows)
    assert keys is not None and keys[1] == keys[4]
    # lexicographic: 1 < x499 < x0 < x0 x499 < x0^2
    assert [int(i) for i in np.argsort(keys, kind="stable")] == [5, 0, 1, 4, 2, 3]
    U, inv = unique_rows(np.repeat(rows, 20, axis=0))          # > SMALL_ROWS: the array path
    assert U.shape[0] == 5 and np.array_equal(U, np.unique(rows, axis=0))
    exps, coef = sum_rows(rows, np.arange(6.0)[:, None])
    assert exps.shape[0] == 5 and coef[np.flatnonzero((exps == rows[1]).all(axis=1))[0], 0] == 1.0 + 4.0

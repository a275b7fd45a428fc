"""Polynomial matrices (sosdyn.poly.matrix): algebra with numeric matrices, symmetry, shapes."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix


def test_polymatrix_algebra_and_symmetry_check():
    x, y = sd.variables("x y")
    M = PolyMatrix([[1 + x**2, x * y], [x * y, 2.0]])
    A = np.array([[0.0, 1.0], [-2.0, -3.0]])
    G = A.T @ M + M @ A
    assert G.is_symmetric()
    vals = G([[0.3, -0.7]], [x, y])[0]
    Mv = M([[0.3, -0.7]], [x, y])[0]
    np.testing.assert_allclose(vals, A.T @ Mv + Mv @ A)
    with pytest.raises(sd.NotSymmetricError, match="differ"):
        PolyMatrix([[x, y], [x, 1]]).check_symmetric()
    with pytest.raises(sd.PolynomialError):
        _ = M @ np.ones((3, 3))


"""The face a solver's kernel names, read in rationals (sosdyn.sos.kernel).

Known answer: Q = U R U^T with U's columns orthogonal to k = (1, 1, 1, 1) and R positive definite
has the kernel k exactly; a solver's Q near it is off by about the square root of its tolerance.
"""
import numpy as np

from sosdyn.sos.kernel import ROUNDINGS, rational_face


def noisy_gram(noise, seed=0):
    rng = np.random.default_rng(seed)
    U = np.array([[1, 0, 0], [-1, 1, 0], [0, -1, 1], [0, 0, -1]], dtype=float)    # U^T (1, 1, 1, 1) = 0
    A = rng.standard_normal((3, 3))
    Q = U @ (A @ A.T + np.eye(3)) @ U.T
    E = rng.standard_normal((4, 4))
    return Q + noise * np.abs(Q).max() * (E + E.T) / 2


def test_an_integer_kernel_is_read_exactly_through_noise_the_fine_rounding_misreads():
    # noise 1e-3 moves the kernel's echelon entries by about 1e-3: with denominators up to 1000
    # they round to a wrong rational (or to none); rounded to integers they give k itself
    Q = noisy_gram(1e-3)
    U = rational_face(Q, tol=1e-2, rounding=ROUNDINGS[0])
    assert U is not None and len(U[0]) == 3
    assert all(sum(row[a] for row in U) == 0 for a in range(3))          # U^T k = 0, exactly
    fine = rational_face(Q, tol=1e-2, rounding=ROUNDINGS[-1])
    assert fine is None or any(sum(row[a] for row in fine) != 0 for a in range(len(fine[0])))

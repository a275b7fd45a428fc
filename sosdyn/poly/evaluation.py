"""Monomial values and gradients at many points: the one vectorised evaluation of z^e.

For exponent rows e_j (an (m, n) array, :mod:`.monomials`) and points z (rows of Z, (N, n)):

* ``monomial_values``:    V[p, j]    = prod_i z_pi^e_ji
* ``monomial_gradients``: D[p, i, j] = d z^e_j / d z_i = e_ji z^(e_j - u_i)   (u_i the unit row)

Every polynomial evaluation in sosdyn goes through them (``Polynomial.__call__``, the
learner's fields and metrics), so a number is computed the same way wherever it is needed.
The points are taken as given (callers check them: ``checks.finite_points``).
"""
from __future__ import annotations

import numpy as np


def monomial_values(Z: np.ndarray, exps: np.ndarray) -> np.ndarray:
    """(N, m) values z^e_j at the rows of Z."""
    out = np.ones((Z.shape[0], exps.shape[0]))
    for i in range(exps.shape[1]):
        if exps[:, i].any():
            out *= Z[:, i:i + 1] ** exps[None, :, i]
    return out


def monomial_gradients(Z: np.ndarray, exps: np.ndarray) -> np.ndarray:
    """(N, n, m): d z^e_j / d z_i at the rows of Z."""
    N, n = Z.shape
    out = np.zeros((N, n, exps.shape[0]))
    for i in range(n):
        e = exps[:, i]
        lowered = exps.copy()
        lowered[:, i] = np.maximum(e - 1, 0)
        out[:, i, :] = monomial_values(Z, lowered) * e[None, :]
    return out

"""An SOS polynomial written out as a sum of squares, from its verified Gram matrix.

z(x)^T Q z(x) with Q >= 0 is factored by a pivoted LDL^T (at each step the largest remaining
diagonal entry d_k is the pivot k: Q <- Q - d_k l_k l_k^T with l_k = Q[:, k] / d_k, so
l_k[k] = 1), stopping when every remaining diagonal entry is below ``rel_tol * max diag Q``:

    z^T Q z  ~=  sum_k d_k (l_k^T z(x))^2,

each square led by its pivot monomial with coefficient 1. The numbers are rounded to
``digits`` significant digits *before* the sum is formed, so :meth:`SOSDecomposition.polynomial`
is exactly the printed sum; it reproduces z^T Q z to about 10^-digits times max|Q| (plus the
dropped remainder, below rel_tol * max diag Q per entry).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..poly import Polynomial


def _round(a, digits: int) -> np.ndarray:
    """Round each entry to ``digits`` significant digits."""
    return np.array([float(f"{v:.{digits}g}") for v in np.ravel(a)]).reshape(np.shape(a))


@dataclass
class SOSDecomposition:
    """sum_k weights[k] * squares[k]^2 (numeric polynomials, coefficients as printed)."""

    weights: np.ndarray
    squares: list

    def polynomial(self) -> Polynomial:
        """The sum of squares as one polynomial (exactly the printed numbers)."""
        vars = self.squares[0].vars if self.squares else ()
        return sum((w * q**2 for w, q in zip(self.weights, self.squares)), Polynomial.constant(0.0, vars))

    def __len__(self) -> int:
        return len(self.squares)

    def __str__(self) -> str:
        if not self.squares:
            return "0"
        return " + ".join(f"{w:g}*({q!r})^2" for w, q in zip(self.weights, self.squares))

    __repr__ = __str__


def sos_decomposition(vars, basis: np.ndarray, Q: np.ndarray, digits: int = 6,
                      rel_tol: float = 1e-12) -> SOSDecomposition:
    """The pivoted LDL^T sum of squares of z(x)^T Q z(x) (module doc); ``basis`` rows are z's exponents."""
    R = 0.5 * (Q + Q.T)
    floor = rel_tol * max(float(np.diag(R).max(initial=0.0)), 0.0)
    weights, squares = [], []
    for _ in range(R.shape[0]):
        k = int(np.argmax(np.diag(R)))
        d = R[k, k]
        if d <= floor:
            break
        col = R[:, k] / d
        R = R - d * np.outer(col, col)
        col[k] = 1.0
        keep = np.abs(col) > 0.5 * 10.0 ** -digits
        weights.append(float(_round(d, digits)))
        squares.append(Polynomial(vars, basis[keep], _round(col[keep], digits)))
    return SOSDecomposition(np.array(weights), squares)

"""Objectives of SOS programs: affine scalars and convex quadratics in decision variables.

A :class:`QuadraticForm` is f(d) = d^T P d + q^T d + c over the decision ids ``ids``
(P symmetric PSD). :func:`sum_squares` builds one from affine residuals, which is how the
learner's least-squares fit (paper eq. 18) reaches the solver without an epigraph cone.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import PolynomialError
from ..poly import Polynomial


def is_cvxpy(obj) -> bool:
    """True for a cvxpy expression or constraint (checked without importing cvxpy)."""
    return type(obj).__module__.split(".")[0] == "cvxpy"


def affine_rows(exprs, ids=None):
    """Stack degree-0 affine polynomials as (c0, C, ids) with value = c0 + C @ d[ids]."""
    exprs = [e if isinstance(e, Polynomial) else Polynomial.constant(float(e)) for e in exprs]
    for e in exprs:
        if not e.is_constant:
            raise PolynomialError(f"expected a constant (degree-0) affine expression, got {e!r}")
    if ids is None:
        ids = np.unique(np.concatenate([e.ids for e in exprs] + [np.zeros(0, dtype=np.int64)]))
    c0 = np.zeros(len(exprs))
    C = np.zeros((len(exprs), ids.size))
    for r, e in enumerate(exprs):
        if e.nterms:
            c0[r] = e.coef[0, 0]
            C[r, np.searchsorted(ids, e.ids)] = e.coef[0, 1:]
    return c0, C, ids


class QuadraticForm:
    """f(d) = d^T P d + q^T d + c over decision ids ``ids`` (see module docstring)."""

    def __init__(self, P, q, c, ids):
        self.P = np.asarray(P, dtype=float)
        self.q = np.asarray(q, dtype=float)
        self.c = float(c)
        self.ids = np.asarray(ids, dtype=np.int64)

    @classmethod
    def from_residuals(cls, C, c0, ids) -> "QuadraticForm":
        """||C d + c0||^2, compressed to a (k x k) form whatever the number of rows."""
        C = np.asarray(C, dtype=float)
        c0 = np.asarray(c0, dtype=float)
        return cls(C.T @ C, 2.0 * C.T @ c0, c0 @ c0, ids)

    def _aligned(self, ids):
        idx = np.searchsorted(ids, self.ids)
        P = np.zeros((ids.size, ids.size))
        P[np.ix_(idx, idx)] = self.P
        q = np.zeros(ids.size)
        q[idx] = self.q
        return P, q

    def __add__(self, other):
        if isinstance(other, Number):
            return QuadraticForm(self.P, self.q, self.c + other, self.ids)
        if isinstance(other, Polynomial):
            c0, C, ids = affine_rows([other])
            other = QuadraticForm(np.zeros((ids.size, ids.size)), C[0], c0[0], ids)
        if not isinstance(other, QuadraticForm):
            return NotImplemented
        ids = np.union1d(self.ids, other.ids)
        (P1, q1), (P2, q2) = self._aligned(ids), other._aligned(ids)
        return QuadraticForm(P1 + P2, q1 + q2, self.c + other.c, ids)

    __radd__ = __add__

    def __mul__(self, k):
        if not isinstance(k, Number) or k < 0:
            raise PolynomialError("a quadratic form can only be scaled by a non-negative number")
        return QuadraticForm(self.P * k, self.q * k, self.c * k, self.ids)

    __rmul__ = __mul__

    def value(self, d: np.ndarray) -> float:
        return float(d @ self.P @ d + self.q @ d + self.c)


def sum_squares(exprs) -> QuadraticForm:
    """sum_i e_i(d)^2 for degree-0 affine expressions e_i (Polynomials or numbers)."""
    c0, C, ids = affine_rows(list(exprs))
    return QuadraticForm.from_residuals(C, c0, ids)

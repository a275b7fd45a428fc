"""Matrices of polynomials: M(x), Jacobians, and the contraction operator's building blocks.

A :class:`PolyMatrix` is a 2-D array of :class:`Polynomial` entries (an object array), so
numeric matrices combine with it by the usual operators: ``A.T @ M + M @ A``. Entries and
numeric operands obey the polynomial layer's rules (:mod:`.polynomial`: real, finite,
|c| <= 1e150), and so do evaluation points.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import NotSymmetricError, PolynomialError
from .checks import finite_points, real_array
from .polynomial import Polynomial, variable_names


def _entry(value, vars=()) -> Polynomial:
    if isinstance(value, Polynomial):
        return value
    if isinstance(value, Number) or (isinstance(value, np.ndarray) and value.ndim == 0):
        return Polynomial.constant(real_array(value, "a matrix entry"), vars)
    raise PolynomialError(f"matrix entry {value!r} is neither a number nor a Polynomial")


class PolyMatrix:
    """A 2-D matrix with polynomial entries (see module docstring)."""

    __array_ufunc__ = None  # numpy operands defer to our reflected operators

    def __init__(self, entries):
        arr = np.array(entries, dtype=object)
        if arr.ndim == 1:
            arr = arr.reshape(-1, 1)
        if arr.ndim != 2:
            raise PolynomialError(f"a PolyMatrix needs a 2-D array of entries, got ndim={arr.ndim}")
        out = np.empty(arr.shape, dtype=object)
        for idx, v in np.ndenumerate(arr):
            out[idx] = _entry(v)
        self.entries = out

    # ------------------------------------------------------------------ construction
    @classmethod
    def identity(cls, n: int, scale: float = 1.0) -> "PolyMatrix":
        return cls(np.eye(n) * scale)

    # ------------------------------------------------------------------ properties
    @property
    def shape(self):
        return self.entries.shape

    @property
    def T(self) -> "PolyMatrix":
        return PolyMatrix(self.entries.T)

    @property
    def vars(self) -> tuple:
        out: list = []
        for p in self.entries.flat:
            out += [v for v in p.vars if v not in out]
        return tuple(out)

    @property
    def ids(self) -> np.ndarray:
        """Sorted decision ids of all entries."""
        return np.unique(np.concatenate([p.ids for p in self.entries.flat] + [np.zeros(0, dtype=np.int64)]))

    @property
    def degree(self) -> int:
        return max(p.degree for p in self.entries.flat)

    @property
    def is_numeric(self) -> bool:
        return all(p.is_numeric for p in self.entries.flat)

    def __getitem__(self, idx):
        got = self.entries[idx]
        return PolyMatrix(got) if isinstance(got, np.ndarray) else got

    def __iter__(self):
        return iter(self.entries)

    # ------------------------------------------------------------------ arithmetic
    @staticmethod
    def _operand(other):
        if isinstance(other, PolyMatrix):
            return other.entries
        if isinstance(other, (Polynomial, Number)):
            return other
        arr = np.asarray(other)
        if arr.dtype == object:
            return arr
        return real_array(arr, "a matrix operand")

    def _check_same_shape(self, other):
        if isinstance(other, np.ndarray) and other.ndim and other.shape != self.shape:
            raise PolynomialError(f"shape mismatch: {self.shape} and {other.shape}")

    def __add__(self, other):
        other = self._operand(other)
        self._check_same_shape(other)
        return PolyMatrix(self.entries + other)

    __radd__ = __add__

    def __neg__(self):
        return PolyMatrix(-self.entries)

    def __sub__(self, other):
        return self + (-PolyMatrix(self._operand(other)) if isinstance(other, (PolyMatrix, np.ndarray, list)) else -other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, (Polynomial, Number)):
            return self.map(lambda p: p * other)
        raise PolynomialError("use @ for matrix products; * takes a scalar or a Polynomial")

    __rmul__ = __mul__

    def __matmul__(self, other):
        other = self._operand(other)
        if not isinstance(other, np.ndarray):
            raise PolynomialError("@ needs a matrix operand")
        other = other.reshape(-1, 1) if other.ndim == 1 else other
        if self.shape[1] != other.shape[0]:
            raise PolynomialError(f"cannot multiply {self.shape} by {other.shape}")
        return PolyMatrix(self.entries @ other)

    def __rmatmul__(self, other):
        other = self._operand(other)
        other = other.reshape(1, -1) if other.ndim == 1 else other
        if other.shape[1] != self.shape[0]:
            raise PolynomialError(f"cannot multiply {other.shape} by {self.shape}")
        return PolyMatrix(other @ self.entries)

    # ------------------------------------------------------------------ calculus
    def map(self, fn) -> "PolyMatrix":
        """Apply ``fn`` to every entry."""
        out = np.empty(self.shape, dtype=object)
        for idx, p in np.ndenumerate(self.entries):
            out[idx] = fn(p)
        return PolyMatrix(out)

    def diff(self, var: str) -> "PolyMatrix":
        return self.map(lambda p: p.diff(var))

    def directional_derivative(self, field, vars) -> "PolyMatrix":
        """dM(x)[v(x)]: entry-wise sum_i (dM/dx_i) v_i(x) -- the Mdot of eq. (4)."""
        vars = variable_names(vars)
        return self.map(lambda p: p.directional_derivative(list(field), vars))

    def assign(self, ids, values) -> "PolyMatrix":
        return self.map(lambda p: p.assign(ids, values))

    # ------------------------------------------------------------------ evaluation
    def __call__(self, X, vars) -> np.ndarray:
        """Values at the rows of X: array of shape (N, rows, cols)."""
        vars = variable_names(vars)
        X = finite_points(X).reshape(-1, len(vars))
        out = np.empty((X.shape[0],) + self.shape)
        for (i, j), p in np.ndenumerate(self.entries):
            out[:, i, j] = p(X, vars)
        return out

    def is_symmetric(self, atol: float = 1e-12) -> bool:
        r, c = self.shape
        return r == c and all(self.entries[i, j].allclose(self.entries[j, i], atol)
                              for i in range(r) for j in range(i + 1, r))

    def check_symmetric(self, what: str = "matrix", atol: float = 1e-12) -> "PolyMatrix":
        """Raise :class:`NotSymmetricError` naming the first asymmetric entry pair."""
        r, c = self.shape
        if r != c:
            raise NotSymmetricError(f"{what} must be square, got shape {self.shape}")
        for i in range(r):
            for j in range(i + 1, r):
                if not self.entries[i, j].allclose(self.entries[j, i], atol):
                    diff = self.entries[i, j] - self.entries[j, i]
                    raise NotSymmetricError(
                        f"{what} is not symmetric: entries ({i},{j}) and ({j},{i}) differ by "
                        f"{_short(diff)}; symmetrise it, e.g. (P + P.T) * 0.5")
        return self

    def __repr__(self) -> str:
        rows = ["[" + ", ".join(repr(p) for p in row) + "]" for row in self.entries]
        return "PolyMatrix([" + ",\n           ".join(rows) + "])"


def _short(p, limit: int = 120) -> str:
    text = repr(p)
    return text if len(text) <= limit else text[:limit] + " ..."


def jacobian(field, vars) -> PolyMatrix:
    """J_ij = d f_i / d x_j of a polynomial vector field f (a sequence of Polynomials)."""
    vars = variable_names(vars)
    return PolyMatrix([[f.diff(v) if isinstance(f, Polynomial) else Polynomial.constant(0.0)
                        for v in vars] for f in field])

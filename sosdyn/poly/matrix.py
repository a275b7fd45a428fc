"""Matrices of polynomials: M(x), Jacobians, and the contraction operator's building blocks.

A :class:`PolyMatrix` is a 2-D array of :class:`Polynomial` entries (an object array), so
numeric matrices combine with it by the usual operators: ``A.T @ M + M @ A``. Entries and
numeric operands obey the polynomial layer's rules (:mod:`.polynomial`: real, finite,
|c| <= 1e150), and so do evaluation points.

Products, sums and the symmetry check run on flat term arrays (:mod:`.termarrays`: one join
and one sort per operation, no loop over entry pairs) whenever the polynomial entries share
one variable tuple; a PolyMatrix keeps its term arrays (entries never change in place), so a
matrix used in many products is decomposed once.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import NotSymmetricError, PolynomialError
from .checks import finite_points, real_array
from .polynomial import Polynomial, variable_names
from .termarrays import (Terms, combine, concat_terms, matrix_terms, terms_entries, terms_matmul, terms_scale,
                         terms_transpose)

SMALL_SIDE = 4      # asymmetry of square matrices up to this size: entry by entry (no term sort)


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
        self._cache: dict = {}                      # vars and term arrays: entries never change in place
        if all(type(v) is Polynomial for v in arr.flat):
            self.entries = arr                      # np.array made a new array: nothing shared
            return
        out = np.empty(arr.shape, dtype=object)
        numbers: dict = {}                          # one constant Polynomial per distinct number
        for idx, v in np.ndenumerate(arr):
            if isinstance(v, Polynomial):
                out[idx] = v
            else:
                key = (type(v), v) if isinstance(v, Number) else None
                if key is None or key not in numbers:
                    entry = _entry(v)
                    if key is None:
                        out[idx] = entry
                        continue
                    numbers[key] = entry
                out[idx] = numbers[key]
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
        out = PolyMatrix(self.entries.T)
        out._cache = {k: terms_transpose(v) if isinstance(v, Terms) else v for k, v in self._cache.items()}
        return out

    @classmethod
    def from_terms(cls, t: Terms, shape, vars) -> "PolyMatrix":
        """The matrix of term arrays ``t`` over ``vars``; the combined terms are kept for later products."""
        t, _ = combine(t)
        out = cls(terms_entries(t, shape, vars))
        out._cache.update({("terms", vars): t, "vars": vars, "var_tuples": {vars}})
        return out

    @property
    def vars(self) -> tuple:
        if "vars" not in self._cache:
            out: list = []
            for vars in dict.fromkeys(p.vars for p in self.entries.flat):
                out += [v for v in vars if v not in out]
            self._cache["vars"] = tuple(out)
        return self._cache["vars"]

    def terms(self, vars) -> Terms:
        """The entries' term arrays over ``vars`` (:mod:`.termarrays`), computed once per vars."""
        key = ("terms", tuple(vars))
        if key not in self._cache:
            self._cache[key] = matrix_terms(self.entries, tuple(vars))
        return self._cache[key]

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
        right = other if isinstance(other, PolyMatrix) else None
        other = self._operand(other)
        self._check_same_shape(other)
        if isinstance(other, np.ndarray) and other.shape == self.shape:
            vars = _shared_vars(self, right or other)
            if vars is not None:           # on term arrays: one sort for the whole matrix
                t = concat_terms(self.terms(vars), _terms_of(right or other, vars))
                return PolyMatrix.from_terms(t, self.shape, vars)
        return PolyMatrix(self.entries + other)

    __radd__ = __add__

    def __neg__(self):
        out = PolyMatrix(-self.entries)
        out._cache = {k: terms_scale(v, -1.0) if isinstance(v, Terms) else v for k, v in self._cache.items()}
        return out

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
        right = other if isinstance(other, PolyMatrix) else None
        other = self._operand(other)
        if not isinstance(other, np.ndarray):
            raise PolynomialError("@ needs a matrix operand")
        other = other.reshape(-1, 1) if other.ndim == 1 else other
        if self.shape[1] != other.shape[0]:
            raise PolynomialError(f"cannot multiply {self.shape} by {other.shape}")
        return matrix_product(self, right or other)

    def __rmatmul__(self, other):
        other = self._operand(other)
        other = other.reshape(1, -1) if other.ndim == 1 else other
        if other.shape[1] != self.shape[0]:
            raise PolynomialError(f"cannot multiply {other.shape} by {self.shape}")
        return matrix_product(other, self)

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

    def asymmetry(self) -> np.ndarray:
        """(r, r) array: the largest |coefficient| of P_ij - P_ji relative to max(1, the largest
        |coefficient| of P), so that round-off of large products is not asymmetry (one sort; for
        a small square matrix, entry by entry: P_ij - P_ji on the fast path of small polynomials)."""
        r, c = self.shape
        if r == c and r <= SMALL_SIDE:
            out = np.zeros(self.shape)
            for i in range(r):
                for j in range(i + 1, r):
                    out[i, j] = out[j, i] = np.abs((self.entries[i, j] - self.entries[j, i]).coef).max(initial=0.0)
            return out / max([1.0] + [float(np.abs(p.coef).max(initial=0.0)) for p in self.entries.flat])
        t = self.terms(self.vars)
        d, _ = combine(concat_terms(t, terms_scale(terms_transpose(t), -1.0)))
        out = np.zeros(self.shape)
        np.maximum.at(out, (d.row, d.col), np.abs(d.val))
        return out / max(1.0, float(np.abs(t.val).max(initial=0.0)))

    def is_symmetric(self, atol: float = 1e-12) -> bool:
        r, c = self.shape
        return r == c and bool((self.asymmetry() <= atol).all())

    def check_symmetric(self, what: str = "matrix", atol: float = 1e-12) -> "PolyMatrix":
        """Raise :class:`NotSymmetricError` naming the first entry pair (row-major) whose difference
        exceeds ``atol`` relative to max(1, the largest |coefficient|)."""
        r, c = self.shape
        if r != c:
            raise NotSymmetricError(f"{what} must be square, got shape {self.shape}")
        bad = np.argwhere(np.triu(self.asymmetry() > atol, 1))
        if bad.size:
            i, j = (int(v) for v in bad[0])
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


def matrix_product(a, b) -> PolyMatrix:
    """a @ b for PolyMatrices or 2-D arrays of Polynomials or numbers: on term arrays (one join,
    one sort) when the polynomial entries share one variable tuple (every entry of the result is
    then over it), else entry by entry."""
    vars = _shared_vars(a, b)
    if vars is None:
        return PolyMatrix(_entries_of(a) @ _entries_of(b))
    return PolyMatrix.from_terms(terms_matmul(_terms_of(a, vars), _terms_of(b, vars)), (a.shape[0], b.shape[1]), vars)


def _terms_of(x, vars) -> Terms:
    return x.terms(vars) if isinstance(x, PolyMatrix) else matrix_terms(x, vars)


def _entries_of(x) -> np.ndarray:
    return x.entries if isinstance(x, PolyMatrix) else x


def _var_tuples(x) -> set:
    """The distinct non-empty variable tuples of the Polynomial entries of x."""
    if isinstance(x, PolyMatrix):
        if "var_tuples" not in x._cache:
            x._cache["var_tuples"] = _var_tuples(x.entries)
        return x._cache["var_tuples"]
    return {p.vars for p in np.asarray(x, dtype=object).flat if isinstance(p, Polynomial) and p.vars}


def _shared_vars(*operands):
    """The one variable tuple of the operands' non-constant-free Polynomial entries, or None."""
    found = set().union(*(_var_tuples(x) for x in operands))
    return found.pop() if len(found) == 1 else None


def jacobian(field, vars) -> PolyMatrix:
    """J_ij = d f_i / d x_j of a polynomial vector field f (a sequence of Polynomials)."""
    vars = variable_names(vars)
    return PolyMatrix([[f.diff(v) if isinstance(f, Polynomial) else Polynomial.constant(0.0)
                        for v in vars] for f in field])



"""Sparse multivariate polynomials with coefficients affine in decision variables.

A :class:`Polynomial` p(v) = sum_i c_i(d) v^alpha_i stores

* ``vars``  -- tuple of indeterminate names (v_1, ..., v_n),
* ``exps``  -- (m, n) int array, row i = alpha_i (unique rows, sorted),
* ``coef``  -- (m, 1 + k) float array: column 0 the constant part of c_i, column j the
  coefficient of decision variable ``ids[j-1]`` (so c_i(d) = coef[i,0] + coef[i,1:] @ d),
* ``ids``   -- (k,) sorted int array of decision-variable ids (:mod:`.decision`).

A numeric polynomial has k = 0. Products are allowed when at most one factor depends on
decision variables, so every result stays affine in d (the form an SOS program needs).

Admissible data (:mod:`.checks`, applied whenever a polynomial is made, so also after every
operation): real, finite coefficients with |c| <= ``MAX_COEFFICIENT`` = 1e150 (an operation
whose result breaks the rule -- an overflow -- raises too); non-negative integer exponents of
total degree <= ``MAX_DEGREE``, checked before a power is expanded (``canonical=True`` marks
exponent rows already in canonical form, made by sosdyn itself: they are not checked again);
arrays of products and of combining like terms within ``sosdyn.limits``; finite evaluation
points. Evaluation is :func:`.evaluation.monomial_values` times the coefficients.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import PolynomialError
from .checks import (check_coefficients, check_degree, check_exponents, check_terms_size, finite_points,
                     real_array)
from .evaluation import monomial_values
from .monomials import MAX_DEGREE, match_rows, sum_rows


def _scalar(value) -> float:
    return float(real_array(value, "a scalar operand"))


class Polynomial:
    """A polynomial whose coefficients are affine in decision variables (see module doc)."""

    __slots__ = ("vars", "exps", "coef", "ids")
    __array_ufunc__ = None  # numpy scalars and arrays defer to our reflected operators

    def __init__(self, vars, exps, coef, ids=None, *, canonical: bool = False):
        self.vars = tuple(vars)
        coef = real_array(coef)
        if coef.ndim == 1:
            coef = coef[:, None]
        exps = check_exponents(np.asarray(exps))
        exps = exps.reshape(coef.shape[0], len(self.vars)) if exps.size or not self.vars \
            else exps.reshape(-1, len(self.vars))
        ids = np.zeros(0, dtype=np.int64) if ids is None else np.asarray(ids, dtype=np.int64)
        if coef.shape != (exps.shape[0], 1 + ids.size):
            raise PolynomialError(
                f"coefficient array of shape {coef.shape} does not fit {exps.shape[0]} "
                f"monomials and {ids.size} decision variables")
        if not canonical and exps.shape[0] > 1:
            check_terms_size(exps.shape[0], exps.shape[1], coef.shape[1], "combining like terms")
        if not canonical and exps.size:
            if exps.min() < 0:
                raise PolynomialError("negative exponents: only polynomials are supported")
            if int(exps.max()) * exps.shape[1] > MAX_DEGREE:     # else no row can exceed it
                check_degree(int(exps.sum(axis=1).max()), "a polynomial")
        check_coefficients(coef)
        if not canonical:
            if exps.shape[0] > 1:
                exps, coef = sum_rows(exps, coef)
            keep = (coef != 0.0).any(axis=1)
            if not keep.all():
                exps, coef = exps[keep], coef[keep]
            if ids.size:
                used = (coef[:, 1:] != 0.0).any(axis=0)
                if not used.all():
                    coef, ids = coef[:, np.concatenate(([True], used))], ids[used]
        self.exps, self.coef, self.ids = exps, coef, ids

    # ------------------------------------------------------------------ construction
    @classmethod
    def constant(cls, value: float, vars=()) -> "Polynomial":
        """The constant polynomial ``value``."""
        return cls(vars, np.zeros((1, len(vars)), dtype=np.int64), [_scalar(value)])

    @classmethod
    def affine(cls, ids, coefs, const: float = 0.0, vars=()) -> "Polynomial":
        """The degree-0 polynomial ``const + sum_j coefs[j] * d[ids[j]]``."""
        ids = np.asarray(ids, dtype=np.int64)
        order = np.argsort(ids)
        row = np.r_[_scalar(const), real_array(coefs)[order]][None, :]
        return cls(vars, np.zeros((1, len(vars)), dtype=np.int64), row, ids[order])

    # ------------------------------------------------------------------ properties
    @property
    def nvars(self) -> int:
        return len(self.vars)

    @property
    def nterms(self) -> int:
        return self.exps.shape[0]

    @property
    def degree(self) -> int:
        """Total degree (-1 for the zero polynomial)."""
        return int(self.exps.sum(axis=1).max()) if self.nterms else -1

    @property
    def is_numeric(self) -> bool:
        """True when no coefficient depends on a decision variable."""
        return self.ids.size == 0

    @property
    def is_constant(self) -> bool:
        return self.degree <= 0

    def degree_in(self, var: str) -> int:
        if var not in self.vars or not self.nterms:
            return 0
        return int(self.exps[:, self.vars.index(var)].max())

    # ------------------------------------------------------------------ alignment
    def with_vars(self, vars) -> "Polynomial":
        """The same polynomial expressed over the variable tuple ``vars`` (a superset)."""
        vars = tuple(vars)
        if vars == self.vars:
            return self
        missing = [v for v in self.vars if v not in vars and self.degree_in(v) > 0]
        if missing:
            raise PolynomialError(f"variables {missing} are not in {vars}")
        exps = np.zeros((self.nterms, len(vars)), dtype=np.int64)
        for j, v in enumerate(self.vars):
            if v in vars:
                exps[:, vars.index(v)] = self.exps[:, j]
        return Polynomial(vars, exps, self.coef, self.ids)

    def with_ids(self, ids) -> "Polynomial":
        """The same polynomial with coefficient columns for the decision ids ``ids`` (a superset)."""
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size == self.ids.size and np.array_equal(ids, self.ids):
            return self
        check_terms_size(self.nterms, 0, 1 + ids.size, "aligning decision variables")
        coef = np.zeros((self.nterms, 1 + ids.size))
        coef[:, 0] = self.coef[:, 0]
        coef[:, 1 + np.searchsorted(ids, self.ids)] = self.coef[:, 1:]
        return Polynomial(self.vars, self.exps, coef, ids, canonical=True)

    def _align(self, other: "Polynomial"):
        if self.vars != other.vars:
            vars = self.vars + tuple(v for v in other.vars if v not in self.vars)
            a, b = self.with_vars(vars), other.with_vars(vars)
        else:
            a, b = self, other
        if a.ids.size != b.ids.size or not np.array_equal(a.ids, b.ids):
            ids = np.union1d(a.ids, b.ids)
            a, b = a.with_ids(ids), b.with_ids(ids)
        return a, b

    def _coerce(self, other) -> "Polynomial":
        if isinstance(other, Polynomial):
            return other
        if isinstance(other, Number) or (isinstance(other, np.ndarray) and other.ndim == 0):
            return Polynomial.constant(other, self.vars)
        return NotImplemented

    # ------------------------------------------------------------------ arithmetic
    def __add__(self, other):
        other = self._coerce(other)
        if other is NotImplemented:
            return NotImplemented
        a, b = self._align(other)
        return Polynomial(a.vars, np.vstack([a.exps, b.exps]), np.vstack([a.coef, b.coef]), a.ids)

    __radd__ = __add__

    def __neg__(self):
        return Polynomial(self.vars, self.exps, -self.coef, self.ids, canonical=True)

    def __sub__(self, other):
        other = self._coerce(other)
        if other is NotImplemented:
            return NotImplemented
        return self + (-other)

    def __rsub__(self, other):
        other = self._coerce(other)
        if other is NotImplemented:
            return NotImplemented
        return other + (-self)

    def __mul__(self, other):
        if isinstance(other, Number) or (isinstance(other, np.ndarray) and other.ndim == 0):
            return Polynomial(self.vars, self.exps, self.coef * _scalar(other), self.ids)
        if not isinstance(other, Polynomial):
            return NotImplemented
        if not self.is_numeric and not other.is_numeric:
            raise PolynomialError(
                "product of two polynomials that both depend on decision variables is not "
                "affine in them (a bilinear term); fix one factor to numbers first")
        a, b = (other, self) if self.is_numeric and not other.is_numeric else (self, other)  # b numeric
        if a.vars != b.vars:
            vars = a.vars + tuple(v for v in b.vars if v not in a.vars)
            a, b = a.with_vars(vars), b.with_vars(vars)
        check_terms_size(a.nterms * b.nterms, a.nvars, a.coef.shape[1], "a product")
        exps = (a.exps[:, None, :] + b.exps[None, :, :]).reshape(a.nterms * b.nterms, a.nvars)
        coef = (a.coef[:, None, :] * b.coef[None, :, :1]).reshape(-1, a.coef.shape[1])
        return Polynomial(a.vars, exps, coef, a.ids)

    __rmul__ = __mul__

    def __truediv__(self, other):
        if isinstance(other, Number) or (isinstance(other, np.ndarray) and other.ndim == 0):
            d = _scalar(other)
            if d == 0.0:
                raise PolynomialError("division of a polynomial by zero")
            return self * (1.0 / d)
        return NotImplemented

    def __pow__(self, k: int):
        if not isinstance(k, (int, np.integer)) or k < 0:
            raise PolynomialError(f"power must be a non-negative integer, got {k!r}")
        check_degree(max(self.degree, 0) * int(k), f"a power p**{k}")
        result, base = Polynomial.constant(1.0, self.vars), self
        while k:
            if k & 1:
                result = result * base
            k >>= 1
            if k:
                base = base * base
        return result

    # ------------------------------------------------------------------ calculus
    def diff(self, var) -> "Polynomial":
        """Partial derivative with respect to the indeterminate ``var`` (a name or a variable).

        A variable absent from ``self.vars`` gives the zero polynomial; anything that is not an
        indeterminate (``2*x``, ``x + 1``, a number) is a PolynomialError, never a silent zero.
        """
        (var,) = variable_names([var])
        if var not in self.vars:
            return Polynomial(self.vars, np.zeros((0, self.nvars)), np.zeros((0, 1 + self.ids.size)), self.ids)
        j = self.vars.index(var)
        e = self.exps[:, j]
        keep = e > 0
        exps = self.exps[keep].copy()
        exps[:, j] -= 1
        return Polynomial(self.vars, exps, self.coef[keep] * e[keep, None], self.ids)

    def gradient(self, vars=None) -> list:
        """[dp/dv for v in vars]."""
        return [self.diff(v) for v in (self.vars if vars is None else vars)]

    def directional_derivative(self, field, vars=None) -> "Polynomial":
        """dp(x)[v(x)] = sum_i (dp/dx_i) v_i(x) for a polynomial vector field v."""
        vars = self.vars if vars is None else variable_names(vars)
        if len(field) != len(vars):
            raise PolynomialError(f"field has {len(field)} components for {len(vars)} variables")
        return sum((self.diff(v) * f for v, f in zip(vars, field)), Polynomial.constant(0.0, vars))

    # ------------------------------------------------------------------ evaluation
    def _points(self, X, vars) -> np.ndarray:
        X = finite_points(X)
        vars = self.vars if vars is None else tuple(vars)
        X = X.reshape(-1, len(vars)) if X.ndim <= 1 else X
        if X.shape[1] != len(vars):
            raise PolynomialError(f"points have {X.shape[1]} columns for variables {vars}")
        cols = []
        for v in self.vars:
            if v not in vars:
                raise PolynomialError(f"no value given for variable {v!r}")
            cols.append(vars.index(v))
        return X[:, cols]

    def monomial_values(self, X, vars=None) -> np.ndarray:
        """(N, m) values of every monomial at N points (rows of X, columns in ``vars``)."""
        return monomial_values(self._points(X, vars), self.exps)

    def evaluate_affine(self, X, vars=None) -> np.ndarray:
        """(N, 1 + k) values: column 0 constant part, column j the coefficient of ids[j-1]."""
        return self.monomial_values(X, vars) @ self.coef

    def __call__(self, X, vars=None) -> np.ndarray:
        """Vectorised evaluation of a numeric polynomial at the rows of X: shape (N,)."""
        if not self.is_numeric:
            raise PolynomialError("polynomial depends on decision variables: use "
                                  "evaluate_affine, or substitute values with assign()")
        return self.monomial_values(X, vars) @ self.coef[:, 0]

    # ------------------------------------------------------------------ substitution
    def assign(self, ids, values) -> "Polynomial":
        """Substitute numbers for the decision variables ``ids`` (others stay)."""
        ids = np.asarray(ids, dtype=np.int64)
        values = real_array(values, "decision values")
        order = np.argsort(ids)
        ids, values = ids[order], values[order]
        hit = np.isin(self.ids, ids)
        pos = np.searchsorted(ids, self.ids[hit])
        const = self.coef[:, 0] + self.coef[:, 1:][:, hit] @ values[pos]
        coef = np.column_stack([const, self.coef[:, 1:][:, ~hit]])
        return Polynomial(self.vars, self.exps, coef, self.ids[~hit])

    def subs(self, mapping: dict) -> "Polynomial":
        """Substitute numbers or polynomials for indeterminates: ``p.subs({"x": 2*y})``."""
        unknown = [v for v in mapping if v not in self.vars]
        if unknown:
            raise PolynomialError(f"cannot substitute {unknown}: not variables of {self.vars}")
        keep = tuple(v for v in self.vars if v not in mapping)
        result = Polynomial.constant(0.0, keep)
        powers: dict = {}
        for i in range(self.nterms):
            term = Polynomial(keep, [[self.exps[i, self.vars.index(v)] for v in keep]],
                              self.coef[i:i + 1], self.ids)
            for v, val in mapping.items():
                e = int(self.exps[i, self.vars.index(v)])
                if e:
                    key = (v, e)
                    if key not in powers:
                        base = val if isinstance(val, Polynomial) else Polynomial.constant(val, keep)
                        powers[key] = base ** e
                    term = term * powers[key]
            result = result + term
        return result

    # ------------------------------------------------------------------ inspection
    def coeff(self, monomial) -> "Polynomial":
        """The (affine) coefficient of one monomial, as a degree-0 polynomial.

        ``monomial`` is an exponent tuple in ``self.vars`` order or a monomial Polynomial.
        """
        if isinstance(monomial, Polynomial):
            if monomial.nterms != 1:
                raise PolynomialError("coeff() takes a single monomial")
            monomial = monomial.with_vars(self.vars + tuple(v for v in monomial.vars if v not in self.vars))
            alpha = monomial.exps[0][:self.nvars]
        else:
            alpha = np.asarray(monomial, dtype=np.int64)
        idx = match_rows(self.exps, alpha.reshape(1, -1))[0]
        row = self.coef[idx:idx + 1] if idx >= 0 else np.zeros((1, 1 + self.ids.size))
        return Polynomial((), np.zeros((1, 0)), row, self.ids)

    def constant_value(self) -> float:
        """The value of a numeric constant polynomial."""
        if not (self.is_numeric and self.is_constant):
            raise PolynomialError("not a numeric constant")
        return float(self.coef[0, 0]) if self.nterms else 0.0

    def allclose(self, other, atol: float = 1e-9) -> bool:
        """Coefficient-wise comparison (numeric and decision parts)."""
        if (isinstance(other, Polynomial) and self.vars == other.vars and self.exps.shape == other.exps.shape
                and np.array_equal(self.ids, other.ids) and np.array_equal(self.exps, other.exps)):
            return bool(np.abs(self.coef - other.coef).max(initial=0.0) <= atol)
        diff = self - other
        return diff.nterms == 0 or bool(np.abs(diff.coef).max() <= atol)

    def __repr__(self) -> str:
        if not self.nterms:
            return "0"
        terms = []
        for i in range(self.nterms):
            mono = "*".join(v if e == 1 else f"{v}^{e}" for v, e in zip(self.vars, self.exps[i]) if e)
            parts = [f"{self.coef[i, 0]:.6g}"] if self.coef[i, 0] else []
            parts += [f"{c:.6g}*d{d}" for c, d in zip(self.coef[i, 1:], self.ids) if c]
            c = parts[0] if len(parts) == 1 else "(" + " + ".join(parts) + ")"
            terms.append(c if not mono else (mono if c == "1" else f"{c}*{mono}"))
        return " + ".join(terms)


def variables(names) -> tuple:
    """Indeterminates by name: ``x, y = variables("x y")``."""
    if isinstance(names, str):
        names = names.replace(",", " ").split()
    names = list(names)
    if len(set(names)) != len(names):
        raise PolynomialError(f"duplicate variable names in {names}")
    return tuple(Polynomial((n,), [[1]], [1.0]) for n in names)


def variable_names(polys) -> tuple:
    """Names of a sequence of indeterminates (degree-1 monomials) in the given order."""
    out = []
    for p in polys:
        if isinstance(p, str):
            out.append(p)
            continue
        if not (isinstance(p, Polynomial) and p.nterms == 1 and p.is_numeric and p.degree == 1
                and p.coef[0, 0] == 1.0):
            raise PolynomialError(f"{p!r} is not an indeterminate (make them with sd.variables)")
        out.append(p.vars[int(np.argmax(p.exps[0]))])
    return tuple(out)

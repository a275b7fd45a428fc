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
operation): real, finite coefficients with |c| <= ``MAX_COEFFICIENT`` = 1e150 (an overflow in an
operation raises too); non-negative integer exponents of total degree <= ``MAX_DEGREE``, checked
before a power or a product is expanded; the arrays of products and of combining like terms within
``sosdyn.limits``; finite evaluation points. An operation on admissible operands checks again only
what it can break (``Polynomial._made``; ``canonical=True`` marks given rows already canonical);
small operations run on plain Python (:mod:`.smallterms`). ``==`` compares by value; evaluation,
variable order and printing: :mod:`.evaluation`, :mod:`.canonical`.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import PolynomialError
from .checks import (admissible_arrays, check_coefficients, check_degree, check_terms_size, ordered_points,
                     real_array)
from . import smallterms as small
from .evaluation import monomial_values
from .monomials import MAX_DEGREE, combine_terms, match_rows, sum_rows
from .canonical import canonical_key, format_terms, merged_vars


def _scalar(value) -> float:
    return float(value) if type(value) in (float, int) else float(real_array(value, "a scalar operand"))


class Polynomial:
    """A polynomial whose coefficients are affine in decision variables (see module doc)."""

    __slots__ = ("vars", "exps", "coef", "ids")
    __array_ufunc__ = None  # numpy scalars and arrays defer to our reflected operators

    def __init__(self, vars, exps, coef, ids=None, *, canonical: bool = False):
        self.vars = tuple(vars)
        exps, coef, ids = admissible_arrays(len(self.vars), exps, coef, ids, canonical)
        if not canonical:
            combine = small.combine if small.fits(exps.shape[0], coef.shape[1]) else combine_terms
            exps, coef, ids = combine(exps, coef, ids)
        self.exps, self.coef, self.ids = exps, coef, ids

    @classmethod
    def _made(cls, vars: tuple, exps, coef, ids, sort: bool = True) -> "Polynomial":
        """The polynomial of arrays an operation computed from admissible polynomials (int64
        exponents >= 0 of checked degree, sorted ids): terms combined (see combine_terms; rows
        sorted when ``sort``), then the coefficients checked, which an operation can overflow."""
        if small.fits(exps.shape[0], coef.shape[1]):
            return cls._bare(vars, *small.combine(exps, coef, ids))
        exps, coef, ids = combine_terms(exps, coef, ids, sort)
        check_coefficients(coef)
        return cls._bare(vars, exps, coef, ids)

    @classmethod
    def _bare(cls, vars: tuple, exps, coef, ids) -> "Polynomial":
        """The polynomial of arrays already admissible and canonical (nothing checked)."""
        self = object.__new__(cls)
        self.vars, self.exps, self.coef, self.ids = vars, exps, coef, ids
        return self

    # ------------------------------------------------------------------ construction
    @classmethod
    def constant(cls, value: float, vars=()) -> "Polynomial":
        """The constant polynomial ``value``."""
        vars = tuple(vars)
        return cls._bare(vars, *small.canonical({(0,) * len(vars): [_scalar(value)]}, len(vars), [], small.NO_IDS))

    @classmethod
    def affine(cls, ids, coefs, const: float = 0.0, vars=()) -> "Polynomial":
        """The degree-0 polynomial ``const + sum_j coefs[j] * d[ids[j]]``."""
        ids = np.asarray(ids, dtype=np.int64)
        order = np.argsort(ids)
        row = np.concatenate(([_scalar(const)], real_array(coefs).reshape(-1)[order]))[None, :]
        return cls._made(tuple(vars), np.zeros((1, len(vars)), dtype=np.int64), row, ids[order], sort=False)

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
        coef = self.coef
        if self.nterms > 1:                 # distinct rows: only sorted again, in the new order
            exps, coef = sum_rows(exps, coef)
        return Polynomial._bare(vars, exps, coef, self.ids)

    def with_ids(self, ids) -> "Polynomial":
        """The same polynomial with coefficient columns for the decision ids ``ids`` (a superset)."""
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size == self.ids.size and np.array_equal(ids, self.ids):
            return self
        check_terms_size(self.nterms, 0, 1 + ids.size, "aligning decision variables")
        coef = np.zeros((self.nterms, 1 + ids.size))
        coef[:, 0] = self.coef[:, 0]
        coef[:, 1 + np.searchsorted(ids, self.ids)] = self.coef[:, 1:]
        return Polynomial._bare(self.vars, self.exps, coef, ids)

    def _align(self, other: "Polynomial"):
        if self.vars != other.vars:
            vars = merged_vars(self.vars, other.vars)
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
    def _sum(self, other, sign: float):
        """self + sign * other (sign 1 or -1); small operands on the Python path (:mod:`.smallterms`)."""
        n, k = self.nterms + other.nterms, 1 + self.ids.size + other.ids.size
        if small.fits(n, k):
            vars = merged_vars(self.vars, other.vars)
            check_terms_size(n, len(vars), k, "combining like terms")
            return Polynomial._bare(vars, *small.add(self, other, sign, vars))
        a, b = self._align(other if sign > 0 else -other)
        check_terms_size(a.nterms + b.nterms, a.nvars, a.coef.shape[1], "combining like terms")
        return Polynomial._made(a.vars, np.vstack([a.exps, b.exps]), np.vstack([a.coef, b.coef]), a.ids)

    def __add__(self, other):
        other = self._coerce(other)
        return NotImplemented if other is NotImplemented else self._sum(other, 1.0)

    __radd__ = __add__

    def __neg__(self):
        return Polynomial._bare(self.vars, self.exps, -self.coef, self.ids)     # admissible and canonical still

    def __sub__(self, other):
        other = self._coerce(other)
        return NotImplemented if other is NotImplemented else self._sum(other, -1.0)

    def __rsub__(self, other):
        other = self._coerce(other)
        return NotImplemented if other is NotImplemented else other._sum(self, -1.0)

    def __mul__(self, other):
        if isinstance(other, Number) or (isinstance(other, np.ndarray) and other.ndim == 0):
            if small.fits(self.nterms, self.coef.shape[1]):
                return Polynomial._bare(self.vars, *small.scale(self.exps, self.coef, self.ids, _scalar(other)))
            return Polynomial._made(self.vars, self.exps, self.coef * _scalar(other), self.ids, sort=False)
        if not isinstance(other, Polynomial):
            return NotImplemented
        if not self.is_numeric and not other.is_numeric:
            raise PolynomialError(
                "product of two polynomials that both depend on decision variables is not "
                "affine in them (a bilinear term); fix one factor to numbers first")
        a, b = (other, self) if self.is_numeric and not other.is_numeric else (self, other)  # b numeric
        vars = merged_vars(a.vars, b.vars)
        check_terms_size(a.nterms * b.nterms, len(vars), a.coef.shape[1], "a product")
        if small.fits(a.nterms * b.nterms, a.coef.shape[1], small.SMALL_PRODUCT_CELLS):
            return Polynomial._bare(vars, *small.multiply(a, b, vars))
        a, b = a.with_vars(vars), b.with_vars(vars)
        exps = (a.exps[:, None, :] + b.exps[None, :, :]).reshape(a.nterms * b.nterms, a.nvars)
        if int(exps.max(initial=0)) * a.nvars > MAX_DEGREE:      # else no row can exceed it
            check_degree(int(exps.sum(axis=1).max()), "a product")
        coef = (a.coef[:, None, :] * b.coef[None, :, :1]).reshape(-1, a.coef.shape[1])
        return Polynomial._made(a.vars, exps, coef, a.ids)

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
        if self.nterms == 1 and self.is_numeric:          # (c x^a)^k = c^k x^(k a)
            return Polynomial._bare(self.vars, *small.power(self.exps, self.coef, self.ids, int(k)))
        check_degree(max(self.degree, 0) * int(k), f"a power p**{k}")
        result, base = None, self
        while k:
            if k & 1:
                result = base if result is None else result * base
            k >>= 1
            if k:
                base = base * base
        return Polynomial.constant(1.0, self.vars) if result is None else result

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
        exps[:, j] -= 1           # rows stay distinct and in order
        return Polynomial._made(self.vars, exps, self.coef[keep] * e[keep, None], self.ids, sort=False)

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
    def monomial_values(self, X, vars=None) -> np.ndarray:
        """(N, m) values of every monomial at N points (rows of X, columns in ``vars``)."""
        return monomial_values(ordered_points(X, self.vars, vars), self.exps)

    def evaluate_affine(self, X, vars=None) -> np.ndarray:
        """(N, 1 + k) values: column 0 constant part, column j the coefficient of ids[j-1]."""
        return self.monomial_values(X, vars) @ self.coef

    def __call__(self, X, vars=None) -> np.ndarray:
        """Vectorised evaluation of a numeric polynomial: shape (N,).

        ``X`` is a dict {name: values} (by name, any order), or an array whose rows are points
        with columns in ``vars`` order (default ``self.vars``; see :mod:`.terms` for that order).
        """
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
        diff = self - other
        return diff.nterms == 0 or bool(np.abs(diff.coef).max() <= atol)

    def __eq__(self, other):
        """Equality by value: the same coefficients (numeric and decision parts) on the same monomials."""
        other = self._coerce(other)
        if other is NotImplemented:
            return NotImplemented
        return (self - other).nterms == 0

    def __hash__(self) -> int:
        return hash(canonical_key(self.vars, self.exps, self.coef, self.ids))

    def __repr__(self) -> str:
        return format_terms(self.vars, self.exps, self.coef, self.ids)


def variables(names) -> tuple:
    """Indeterminates by name: ``x, y = variables("x y")``."""
    if isinstance(names, str):
        names = names.replace(",", " ").split()
    names = list(names)
    if len(set(names)) != len(names):
        raise PolynomialError(f"duplicate variable names in {names}")
    return tuple(Polynomial._bare((n,), np.ones((1, 1), dtype=np.int64), np.ones((1, 1)), small.NO_IDS) for n in names)


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

"""Sparse multivariate polynomials with coefficients affine in decision variables.

A :class:`Polynomial` p(v) = sum_i c_i(d) v^alpha_i stores

* ``vars``  -- tuple of indeterminate names (v_1, ..., v_n),
* ``exps``  -- (m, n) int array, row i = alpha_i (unique rows, sorted),
* ``coef``  -- (m, 1 + k) float array: column 0 the constant part of c_i, column j the
  coefficient of decision variable ``dec[j-1]`` (so c_i(d) = coef[i,0] + coef[i,1:] @ d),
* ``dec``   -- (k,) sorted int array of decision-variable ids.

A numeric polynomial has k = 0. Products are allowed when at most one factor depends on
decision variables, so every result stays affine in d (the form an SOS program needs).

Admissible data (checked whenever a polynomial is made, so also after every operation):

* coefficients are real and finite with |c| <= ``MAX_COEFFICIENT`` = 1e150, so the product
  of two admissible coefficients is finite (1e300 < 1.8e308, the float64 maximum); NaN, inf,
  complex numbers and larger magnitudes raise :class:`~sosdyn.errors.PolynomialError` (an
  operation whose result breaks the rule -- an overflow -- raises too);
* exponents are non-negative integers and the total degree is <= ``MAX_DEGREE``
  (:mod:`.monomials`), checked before a power is expanded (``canonical=True`` marks exponent
  rows already in canonical form, made by sosdyn itself: they are not checked again);
* the arrays of a product, and of combining like terms, fit ``sosdyn.limits`` (max_bytes),
  checked before they are allocated;
* evaluation points are real and finite.
"""
from __future__ import annotations

from numbers import Number

import numpy as np

from ..errors import PolynomialError
from ..limits import check_bytes
from .monomials import MAX_DEGREE, match_rows, sum_rows

MAX_COEFFICIENT = 1e150
_RESCALE = ("rescale the variables (x = s*u turns c*x^k into c*s^k*u^k) or divide the polynomial "
            "by its largest coefficient, so that the numbers are of moderate size")
_SIZE_HINT = "lower the degrees or the number of variables, or split the expression into smaller parts"


def real_array(values, what: str = "coefficients") -> np.ndarray:
    """``values`` as a float array; :class:`PolynomialError` for complex or non-numeric entries."""
    arr = np.asarray(values)
    if arr.dtype == np.float64:
        return arr
    if arr.dtype.kind == "c" or (arr.dtype == object and any(isinstance(v, complex) for v in arr.flat)):
        raise PolynomialError(f"{what} are complex; sosdyn polynomials have real coefficients and "
                              "are evaluated at real points. Try: pass real numbers (e.g. np.real), "
                              "or split real and imaginary parts into two polynomials")
    try:
        return arr.astype(float)
    except (TypeError, ValueError) as exc:
        raise PolynomialError(f"{what} must be real numbers: {exc}") from None


def finite_points(X, what: str = "evaluation points") -> np.ndarray:
    """Real, finite evaluation points as a float array (PolynomialError otherwise)."""
    X = real_array(X, what)
    if not np.isfinite(X).all():
        raise PolynomialError(f"{what} contain NaN or inf (at flat index "
                              f"{int(np.flatnonzero(~np.isfinite(X))[0])}). Try: evaluate at finite points")
    return X


def check_coefficients(coef: np.ndarray) -> None:
    """Raise PolynomialError unless every entry is finite with |c| <= MAX_COEFFICIENT."""
    if not coef.size or (coef.max() <= MAX_COEFFICIENT and coef.min() >= -MAX_COEFFICIENT):
        return
    if np.isnan(coef).any():
        raise PolynomialError("a coefficient is NaN: a polynomial needs finite numbers. "
                              "Try: remove NaN from the input data")
    if np.isinf(coef).any():
        raise PolynomialError("a coefficient is infinite (an inf in the input, or an overflow in "
                              f"arithmetic). Try: {_RESCALE}")
    worst = float(coef.flat[np.abs(coef).argmax()])
    raise PolynomialError(f"coefficient {worst:.3g} is above {MAX_COEFFICIENT:.0e} in magnitude: "
                          f"numbers this large make any computation with it meaningless in double "
                          f"precision. Try: {_RESCALE}")


def _check_degree(degree: int, what: str) -> None:
    if degree > MAX_DEGREE:
        raise PolynomialError(f"{what} has degree {degree}, above {MAX_DEGREE} (its monomials "
                              "overflow double precision already at |x| = 2). Try: a lower degree")


def check_terms_size(nterms: int, nvars: int, ncoef: int, what: str) -> None:
    """Check against ``sosdyn.limits`` the memory of a polynomial of ``nterms`` terms.

    16 bytes per stored number: the exponent (nterms x nvars) and coefficient
    (nterms x ncoef) arrays, and their sorted copies made while combining like terms.
    """
    check_bytes(16.0 * nterms * (nvars + ncoef), f"{what} ({nterms} terms before combining)", _SIZE_HINT)


def _scalar(value) -> float:
    return float(real_array(value, "a scalar operand"))


class Polynomial:
    """A polynomial whose coefficients are affine in decision variables (see module doc)."""

    __slots__ = ("vars", "exps", "coef", "dec")
    __array_ufunc__ = None  # numpy scalars and arrays defer to our reflected operators

    def __init__(self, vars, exps, coef, dec=None, *, canonical: bool = False):
        self.vars = tuple(vars)
        coef = real_array(coef)
        if coef.ndim == 1:
            coef = coef[:, None]
        exps = np.asarray(exps)
        if exps.dtype != np.int64:
            if exps.size and exps.dtype.kind not in "iu" and not (
                    exps.dtype.kind == "f" and np.isfinite(exps).all() and (exps == np.round(exps)).all()):
                raise PolynomialError(f"exponents must be non-negative integers, got {exps.ravel()[:5]}")
            exps = exps.astype(np.int64)
        exps = exps.reshape(coef.shape[0], len(self.vars)) if exps.size or not self.vars \
            else exps.reshape(-1, len(self.vars))
        dec = np.zeros(0, dtype=np.int64) if dec is None else np.asarray(dec, dtype=np.int64)
        if coef.shape != (exps.shape[0], 1 + dec.size):
            raise PolynomialError(
                f"coefficient array of shape {coef.shape} does not fit {exps.shape[0]} "
                f"monomials and {dec.size} decision variables")
        if not canonical and exps.shape[0] > 1:
            check_terms_size(exps.shape[0], exps.shape[1], coef.shape[1], "combining like terms")
        if not canonical and exps.size:
            if exps.min() < 0:
                raise PolynomialError("negative exponents: only polynomials are supported")
            if int(exps.max()) * exps.shape[1] > MAX_DEGREE:     # else no row can exceed it
                _check_degree(int(exps.sum(axis=1).max()), "a polynomial")
        check_coefficients(coef)
        if not canonical:
            if exps.shape[0] > 1:
                exps, coef = sum_rows(exps, coef)
            keep = (coef != 0.0).any(axis=1)
            if not keep.all():
                exps, coef = exps[keep], coef[keep]
            if dec.size:
                used = (coef[:, 1:] != 0.0).any(axis=0)
                if not used.all():
                    coef, dec = coef[:, np.concatenate(([True], used))], dec[used]
        self.exps, self.coef, self.dec = exps, coef, dec

    # ------------------------------------------------------------------ construction
    @classmethod
    def constant(cls, value: float, vars=()) -> "Polynomial":
        """The constant polynomial ``value``."""
        return cls(vars, np.zeros((1, len(vars)), dtype=np.int64), [_scalar(value)])

    @classmethod
    def affine(cls, dec_ids, coefs, const: float = 0.0, vars=()) -> "Polynomial":
        """The degree-0 polynomial ``const + sum_j coefs[j] * d[dec_ids[j]]``."""
        dec_ids = np.asarray(dec_ids, dtype=np.int64)
        order = np.argsort(dec_ids)
        row = np.r_[_scalar(const), real_array(coefs)[order]][None, :]
        return cls(vars, np.zeros((1, len(vars)), dtype=np.int64), row, dec_ids[order])

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
        return self.dec.size == 0

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
        return Polynomial(vars, exps, self.coef, self.dec)

    def with_dec(self, dec) -> "Polynomial":
        """The same polynomial with coefficient columns for the (superset) ids ``dec``."""
        dec = np.asarray(dec, dtype=np.int64)
        if dec.size == self.dec.size and np.array_equal(dec, self.dec):
            return self
        check_terms_size(self.nterms, 0, 1 + dec.size, "aligning decision variables")
        coef = np.zeros((self.nterms, 1 + dec.size))
        coef[:, 0] = self.coef[:, 0]
        coef[:, 1 + np.searchsorted(dec, self.dec)] = self.coef[:, 1:]
        return Polynomial(self.vars, self.exps, coef, dec, canonical=True)

    def _align(self, other: "Polynomial"):
        if self.vars != other.vars:
            vars = self.vars + tuple(v for v in other.vars if v not in self.vars)
            a, b = self.with_vars(vars), other.with_vars(vars)
        else:
            a, b = self, other
        if a.dec.size != b.dec.size or not np.array_equal(a.dec, b.dec):
            dec = np.union1d(a.dec, b.dec)
            a, b = a.with_dec(dec), b.with_dec(dec)
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
        return Polynomial(a.vars, np.vstack([a.exps, b.exps]), np.vstack([a.coef, b.coef]), a.dec)

    __radd__ = __add__

    def __neg__(self):
        return Polynomial(self.vars, self.exps, -self.coef, self.dec, canonical=True)

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
            return Polynomial(self.vars, self.exps, self.coef * _scalar(other), self.dec)
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
        return Polynomial(a.vars, exps, coef, a.dec)

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
        _check_degree(max(self.degree, 0) * int(k), f"a power p**{k}")
        result, base = Polynomial.constant(1.0, self.vars), self
        while k:
            if k & 1:
                result = result * base
            k >>= 1
            if k:
                base = base * base
        return result

    # ------------------------------------------------------------------ calculus
    def diff(self, var: str) -> "Polynomial":
        """Partial derivative with respect to the indeterminate ``var``."""
        if var not in self.vars:
            return Polynomial(self.vars, np.zeros((0, self.nvars)), np.zeros((0, 1 + self.dec.size)), self.dec)
        j = self.vars.index(var)
        e = self.exps[:, j]
        keep = e > 0
        exps = self.exps[keep].copy()
        exps[:, j] -= 1
        return Polynomial(self.vars, exps, self.coef[keep] * e[keep, None], self.dec)

    def gradient(self, vars=None) -> list:
        """[dp/dv for v in vars]."""
        return [self.diff(v) for v in (self.vars if vars is None else vars)]

    def directional_derivative(self, field, vars=None) -> "Polynomial":
        """dp(x)[v(x)] = sum_i (dp/dx_i) v_i(x) for a polynomial vector field v."""
        vars = self.vars if vars is None else tuple(vars)
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
        Xs = self._points(X, vars)
        out = np.ones((Xs.shape[0], self.nterms))
        for j in range(self.nvars):
            e = self.exps[:, j]
            if e.any():
                out *= Xs[:, j:j + 1] ** e[None, :]
        return out

    def evaluate_affine(self, X, vars=None) -> np.ndarray:
        """(N, 1 + k) values: column 0 constant part, column j the coefficient of dec[j-1]."""
        return self.monomial_values(X, vars) @ self.coef

    def __call__(self, X, vars=None) -> np.ndarray:
        """Vectorised evaluation of a numeric polynomial at the rows of X: shape (N,)."""
        if not self.is_numeric:
            raise PolynomialError("polynomial depends on decision variables: use "
                                  "evaluate_affine, or substitute values with assign()")
        return self.monomial_values(X, vars) @ self.coef[:, 0]

    # ------------------------------------------------------------------ substitution
    def assign(self, dec_ids, values) -> "Polynomial":
        """Substitute numbers for the decision variables ``dec_ids`` (others stay)."""
        dec_ids = np.asarray(dec_ids, dtype=np.int64)
        values = real_array(values, "decision values")
        order = np.argsort(dec_ids)
        dec_ids, values = dec_ids[order], values[order]
        hit = np.isin(self.dec, dec_ids)
        pos = np.searchsorted(dec_ids, self.dec[hit])
        const = self.coef[:, 0] + self.coef[:, 1:][:, hit] @ values[pos]
        coef = np.column_stack([const, self.coef[:, 1:][:, ~hit]])
        return Polynomial(self.vars, self.exps, coef, self.dec[~hit])

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
                              self.coef[i:i + 1], self.dec)
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
        row = self.coef[idx:idx + 1] if idx >= 0 else np.zeros((1, 1 + self.dec.size))
        return Polynomial((), np.zeros((1, 0)), row, self.dec)

    def constant_value(self) -> float:
        """The value of a numeric constant polynomial."""
        if not (self.is_numeric and self.is_constant):
            raise PolynomialError("not a numeric constant")
        return float(self.coef[0, 0]) if self.nterms else 0.0

    def allclose(self, other, atol: float = 1e-9) -> bool:
        """Coefficient-wise comparison (numeric and decision parts)."""
        if (isinstance(other, Polynomial) and self.vars == other.vars and self.exps.shape == other.exps.shape
                and np.array_equal(self.dec, other.dec) and np.array_equal(self.exps, other.exps)):
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
            parts += [f"{c:.6g}*d{d}" for c, d in zip(self.coef[i, 1:], self.dec) if c]
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

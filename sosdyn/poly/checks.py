"""Admissible polynomial data: real, finite, moderate coefficients; degrees; sizes; points.

The rules (see :mod:`.polynomial`, which applies them whenever a polynomial is made):

* coefficients are real and finite with |c| <= ``MAX_COEFFICIENT`` = 1e150, so the product
  of two admissible coefficients is finite (1e300 < 1.8e308, the float64 maximum);
* total degrees are <= ``MAX_DEGREE`` (:mod:`.monomials`);
* the arrays of a product, and of combining like terms, fit ``sosdyn.limits`` (max_bytes);
* evaluation points are real and finite (ordered_points puts them in a polynomial's variable order).

Each check raises :class:`~sosdyn.errors.PolynomialError` (or ResourceLimitError for sizes)
with what to try.
"""
from __future__ import annotations

import numpy as np

from ..errors import PolynomialError
from ..limits import check_bytes
from .monomials import MAX_DEGREE

MAX_COEFFICIENT = 1e150
RESCALE_HINT = ("rescale the variables (x = s*u turns c*x^k into c*s^k*u^k) or divide the polynomial "
                "by its largest coefficient, so that the numbers are of moderate size")
SIZE_HINT = "lower the degrees or the number of variables, or split the expression into smaller parts"


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
    if not coef.size or np.abs(coef).max() <= MAX_COEFFICIENT:     # False for NaN too
        return
    if np.isnan(coef).any():
        raise PolynomialError("a coefficient is NaN: a polynomial needs finite numbers. "
                              "Try: remove NaN from the input data")
    if np.isinf(coef).any():
        raise PolynomialError("a coefficient is infinite (an inf in the input, or an overflow in "
                              f"arithmetic). Try: {RESCALE_HINT}")
    worst = float(coef.flat[np.abs(coef).argmax()])
    raise PolynomialError(f"coefficient {worst:.3g} is above {MAX_COEFFICIENT:.0e} in magnitude: "
                          f"numbers this large make any computation with it meaningless in double "
                          f"precision. Try: {RESCALE_HINT}")


def check_degree(degree: int, what: str) -> None:
    """Raise PolynomialError if ``degree`` is above MAX_DEGREE."""
    if degree > MAX_DEGREE:
        raise PolynomialError(f"{what} has degree {degree}, above {MAX_DEGREE} (its monomials "
                              "overflow double precision already at |x| = 2). Try: a lower degree")


def check_exponents(exps: np.ndarray) -> np.ndarray:
    """Exponents as an int64 array; PolynomialError unless they are integers."""
    if exps.dtype == np.int64:
        return exps
    if exps.size and exps.dtype.kind not in "iu" and not (
            exps.dtype.kind == "f" and np.isfinite(exps).all() and (exps == np.round(exps)).all()):
        raise PolynomialError(f"exponents must be non-negative integers, got {exps.ravel()[:5]}")
    return exps.astype(np.int64)


def admissible_arrays(nvars: int, exps, coef, ids, canonical: bool):
    """(exps, coef, ids) of a polynomial in ``nvars`` variables given by a caller, as int64 /
    float / int64 arrays of matching shapes, checked (module doc); PolynomialError otherwise.
    With ``canonical`` the rows are taken as given (distinct, sorted): sizes and exponents unchecked."""
    coef = real_array(coef)
    if coef.ndim == 1:
        coef = coef[:, None]
    exps = check_exponents(np.asarray(exps))
    exps = exps.reshape(coef.shape[0], nvars) if exps.size or not nvars else exps.reshape(-1, nvars)
    ids = np.zeros(0, dtype=np.int64) if ids is None else np.asarray(ids, dtype=np.int64)
    if coef.shape != (exps.shape[0], 1 + ids.size):
        raise PolynomialError(f"coefficient array of shape {coef.shape} does not fit {exps.shape[0]} "
                              f"monomials and {ids.size} decision variables")
    if not canonical and exps.shape[0] > 1:
        check_terms_size(exps.shape[0], exps.shape[1], coef.shape[1], "combining like terms")
    if not canonical and exps.size:
        if exps.min() < 0:
            raise PolynomialError("negative exponents: only polynomials are supported")
        if int(exps.max()) * exps.shape[1] > MAX_DEGREE:     # else no row can exceed it
            check_degree(int(exps.sum(axis=1).max()), "a polynomial")
    check_coefficients(coef)
    return exps, coef, ids


def check_terms_size(nterms: int, nvars: int, ncoef: int, what: str) -> None:
    """Check against ``sosdyn.limits`` the memory of a polynomial of ``nterms`` terms.

    16 bytes per stored number: the exponent (nterms x nvars) and coefficient
    (nterms x ncoef) arrays, and their sorted copies made while combining like terms.
    """
    check_bytes(16.0 * nterms * (nvars + ncoef), f"{what} ({nterms} terms before combining)", SIZE_HINT)


def ordered_points(X, own: tuple, vars=None) -> np.ndarray:
    """Finite points as rows with columns in ``own`` order (a polynomial's variables).

    ``X`` is a dict {name: values} (one value, or equally many, for each of ``own``), or an
    array whose rows are points with columns in ``vars`` order (default ``own``).
    """
    if isinstance(X, dict):
        missing = [v for v in own if v not in X]
        cols = [finite_points(X[v], f"values of {v!r}").ravel() for v in own if not missing]
        if missing or len({c.size for c in cols} - {1}) > 1:
            raise PolynomialError(f"p(dict) needs one value (or equally many) for each of {own}; "
                                  f"missing {missing}. Try: p({{'x': xs, 'y': ys}}) with every name")
        return np.column_stack(np.broadcast_arrays(*cols)) if cols else np.zeros((1, 0))
    X = finite_points(X)
    vars = own if vars is None else tuple(vars)
    X = X.reshape(-1, len(vars)) if X.ndim <= 1 else X
    if X.shape[1] != len(vars):
        raise PolynomialError(f"points have {X.shape[1]} columns for variables {vars}")
    missing = [v for v in own if v not in vars]
    if missing:
        raise PolynomialError(f"no value given for variables {missing}")
    return X[:, [vars.index(v) for v in own]]

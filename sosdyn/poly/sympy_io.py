"""Conversion between sosdyn polynomials and sympy expressions (the front door for users)."""
from __future__ import annotations

import numpy as np

from ..errors import PolynomialError
from .polynomial import Polynomial, variable_names


def from_sympy(expr, vars) -> Polynomial:
    """A numeric :class:`Polynomial` from a sympy expression polynomial in ``vars``.

    ``vars`` are sympy Symbols, names, or sosdyn indeterminates; their order fixes the
    polynomial's variable order.
    """
    import sympy

    names = tuple(str(v) if isinstance(v, sympy.Symbol) else variable_names([v])[0] for v in vars)
    symbols = [sympy.Symbol(n) for n in names]
    expr = sympy.sympify(expr).subs({s: sympy.Symbol(s.name) for s in sympy.sympify(expr).free_symbols})
    extra = {str(s) for s in expr.free_symbols} - set(names)
    if extra:
        raise PolynomialError(f"expression has symbols {sorted(extra)} not in vars {names}")
    try:
        poly = sympy.Poly(sympy.expand(expr), *symbols)
    except sympy.PolynomialError as exc:
        raise PolynomialError(f"not a polynomial in {names}: {exc}") from None
    terms = poly.terms()
    exps = np.array([t[0] for t in terms], dtype=np.int64).reshape(-1, len(names))
    coef = np.array([float(t[1]) for t in terms])
    return Polynomial(names, exps, coef)


def to_sympy(poly: Polynomial):
    """A sympy expression of ``poly``; decision variables become symbols ``d<id>``."""
    import sympy

    xs = [sympy.Symbol(v) for v in poly.vars]
    ds = [sympy.Symbol(f"d{int(i)}") for i in poly.dec]
    expr = sympy.Integer(0)
    for i in range(poly.nterms):
        c = sympy.nsimplify(poly.coef[i, 0], rational=False) if poly.coef[i, 0] else 0
        c += sum(float(a) * d for a, d in zip(poly.coef[i, 1:], ds) if a)
        expr += c * sympy.Mul(*[x ** int(e) for x, e in zip(xs, poly.exps[i])])
    return expr

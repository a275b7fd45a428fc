"""Conversion between sosdyn polynomials and sympy expressions (the front door for users).

A string is never evaluated as code (no ``eval``, no ``sympy.sympify`` of the raw text): it
is parsed with :mod:`ast` and only polynomial syntax is accepted -- numbers, the given
variable names, ``+ - *``, ``/`` by a constant, ``**`` (or ``^``, read as ``**`` like sympy
does) to a non-negative integer constant, parentheses. Anything else (calls, attributes,
names not in ``vars``, complex literals) raises :class:`~sosdyn.errors.PolynomialError`.
A sympy expression is bounded (degree, number of terms) before sympy expands it.

sympy is imported inside the functions that need it: it takes about a second to import, and
only these conversions use it (``import sosdyn`` stays fast).
"""
from __future__ import annotations

import ast
import math
from numbers import Number

import numpy as np

from ..errors import PolynomialError
from ..limits import check_bytes
from .decision import decision_name
from .monomials import MAX_DEGREE
from .polynomial import Polynomial, variable_names

MAX_SOURCE_CHARS = 10**6      # longest polynomial string accepted by from_sympy
SYMPY_TERM_BYTES = 1024        # memory of one term while sympy expands (its objects, a generous guess)
_SYNTAX = ("numbers, the variables, + - *, / by a constant, ** (or ^) to a non-negative integer, "
           "parentheses")


def from_sympy(expr, vars) -> Polynomial:
    """A numeric :class:`Polynomial` from a sympy expression (or a polynomial string) in ``vars``.

    ``vars`` are sympy Symbols, names, or sosdyn indeterminates; their order fixes the
    polynomial's variable order. A string is parsed, never evaluated (module docstring).
    """
    import sympy                    # lazily (1 s to import): see the module docstring

    names = tuple(str(v) if isinstance(v, sympy.Symbol) else variable_names([v])[0] for v in vars)
    if isinstance(expr, str):
        return parse_polynomial(expr, names)
    if not isinstance(expr, (sympy.Basic, Number)):
        raise PolynomialError(f"from_sympy takes a sympy expression or a polynomial string, got "
                              f"{type(expr).__name__}. Try: build it with sympy symbols or sd.variables")
    expr = sympy.sympify(expr, strict=True)
    expr = expr.subs({s: sympy.Symbol(s.name) for s in expr.free_symbols})
    extra = {str(s) for s in expr.free_symbols} - set(names)
    if extra:
        raise PolynomialError(f"expression has symbols {sorted(extra)} not in vars {names}")
    degree, terms = _expansion_bound(expr)
    if degree is not None:
        terms = float(min(terms, 10**300))
        check_bytes(SYMPY_TERM_BYTES * terms, f"expanding a sympy expression of up to {terms:.3g} terms",
                    "lower the degree, or expand smaller parts and combine them with sosdyn")
    symbols = [sympy.Symbol(n) for n in names]
    try:
        poly = sympy.Poly(sympy.expand(expr), *symbols)
    except sympy.PolynomialError as exc:
        raise PolynomialError(f"not a polynomial in {names}: {exc}") from None
    terms = poly.terms()
    exps = np.array([t[0] for t in terms], dtype=np.int64).reshape(-1, len(names))
    return Polynomial(names, exps, [_real(c) for _, c in terms])


def _real(c) -> float:
    """A sympy coefficient as a float; PolynomialError if it is complex or not a number."""
    import sympy                    # lazily (1 s to import): see the module docstring

    if c.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
        raise PolynomialError(f"coefficient {c} is not finite. Try: remove nan/oo from the expression")
    re, im = c.as_real_imag()
    if im != 0:
        raise PolynomialError(f"complex coefficient {c}: sosdyn polynomials have real coefficients. "
                              "Try: split real and imaginary parts into two polynomials")
    try:
        return float(re)
    except TypeError:
        raise PolynomialError(f"coefficient {c} is not a number") from None


def _expansion_bound(expr):
    """Upper bounds (total degree, number of terms) of a sympy expression, without expanding it.

    degree: deg(a + b) <= max, deg(a b) <= sum, deg(a^k) <= k deg(a) for an integer k >= 0.
    terms: t(a + b) <= t(a) + t(b), t(a b) <= t(a) t(b), t(a^k) <= C(t(a) + k - 1, k) (the
    monomials of degree k in t(a) symbols), and t <= C(v + deg, v) for v free symbols.
    (None, None) where the expression is not of that form (sympy then decides whether it is
    a polynomial). A degree bound above MAX_DEGREE raises PolynomialError.
    """
    import sympy                    # lazily (1 s to import): see the module docstring

    stack, bounds = [(expr, False)], {}
    while stack:                                   # post-order walk, no recursion
        node, done = stack.pop()
        if node.is_Symbol:
            bounds[node] = (1, 1)
        elif node.is_Number or not node.free_symbols:
            bounds[node] = (0, 1)
        elif not done:
            stack.append((node, True))
            stack += [(a, False) for a in node.args if a not in bounds]
        else:
            args = [bounds[a] for a in node.args]
            if any(d is None for d, _ in args):
                bounds[node] = (None, None)
            elif isinstance(node, sympy.Add):
                bounds[node] = (max(d for d, _ in args), sum(t for _, t in args))
            elif isinstance(node, sympy.Mul):
                bounds[node] = (sum(d for d, _ in args), math.prod(t for _, t in args))
            elif isinstance(node, sympy.Pow) and node.exp.is_Integer and node.exp >= 0:
                (d, t), k = args[0], int(node.exp)
                bounds[node] = (d * k, math.comb(t + k - 1, k) if d else 1)
            else:
                bounds[node] = (None, None)
            d, t = bounds[node]
            if d is not None and d > MAX_DEGREE:
                raise PolynomialError(f"the expression has degree up to {d}, above {MAX_DEGREE}; it "
                                      "is not expanded. Try: a lower degree")
            if d is not None:                      # at most every monomial of degree <= d
                bounds[node] = (d, min(t, math.comb(len(node.free_symbols) + d, d)))
    return bounds[expr]


def parse_polynomial(text: str, vars) -> Polynomial:
    """The polynomial written in ``text`` over the variable names ``vars``; never evaluates code.

    Accepted syntax: see the module docstring. Powers and products are computed by
    :class:`Polynomial` arithmetic, so its degree, size and magnitude checks apply.
    """
    names = tuple(vars)
    if len(text) > MAX_SOURCE_CHARS:
        raise PolynomialError(f"polynomial string of {len(text)} characters is longer than "
                              f"{MAX_SOURCE_CHARS}. Try: build the polynomial with sd.variables")
    try:
        tree = ast.parse(text.strip().replace("^", "**"), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise PolynomialError(f"not a polynomial in {names}: cannot parse {_short(text)!r} "
                              f"({type(exc).__name__}). Accepted: {_SYNTAX}") from None
    unit = np.eye(len(names), dtype=np.int64)
    variables = {n: Polynomial(names, unit[i:i + 1], [1.0]) for i, n in enumerate(names)}
    try:
        return _build(tree.body, names, variables)
    except RecursionError:
        raise PolynomialError(f"polynomial string {_short(text)!r} is nested too deeply") from None


def _build(node, names, variables) -> Polynomial:
    """Polynomial arithmetic over a whitelisted syntax tree (see parse_polynomial)."""
    if isinstance(node, ast.Constant):
        if isinstance(node.value, complex):
            raise PolynomialError(f"complex number {node.value!r}: sosdyn polynomials have real "
                                  "coefficients. Try: split real and imaginary parts")
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise PolynomialError(f"not a polynomial in {names}: {node.value!r} is not a number. "
                                  f"Accepted: {_SYNTAX}")
        try:
            return Polynomial.constant(float(node.value), names)
        except OverflowError:
            raise PolynomialError(f"the number {_short(str(node.value))} does not fit a float") from None
    if isinstance(node, ast.Name):
        if node.id not in variables:
            raise PolynomialError(f"expression has symbols [{node.id!r}] not in vars {names}")
        return variables[node.id]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
        p = _build(node.operand, names, variables)
        return -p if isinstance(node.op, ast.USub) else p
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
        signs, parts = [], []                      # a long sum is a left spine: walk it, sum once
        while isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            signs.append(-1.0 if isinstance(node.op, ast.Sub) else 1.0)
            parts.append(_build(node.right, names, variables))
            node = node.left
        parts.append(_build(node, names, variables))
        signs.append(1.0)
        return Polynomial(names, np.vstack([p.exps for p in parts]),
                          np.vstack([s * p.coef for s, p in zip(signs, parts)]))
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        factors = []
        while isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
            factors.append(_build(node.right, names, variables))
            node = node.left
        result = _build(node, names, variables)
        for f in reversed(factors):
            result = result * f
        return result
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
        a, b = _build(node.left, names, variables), _build(node.right, names, variables)
        if not b.is_constant:
            raise PolynomialError(f"not a polynomial in {names}: division by the non-constant {b!r}")
        return a / b.constant_value()
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Pow, ast.BitXor)):
        base, k = _build(node.left, names, variables), _build(node.right, names, variables)
        kv = k.constant_value() if k.is_constant else None
        if kv is None or kv < 0 or kv != int(kv):
            raise PolynomialError(f"not a polynomial in {names}: the exponent {k!r} is not a "
                                  "non-negative integer constant")
        return base ** int(kv)
    what = type(node).__name__
    if isinstance(node, ast.Call):
        what = f"a function call ({ast.unparse(node.func)[:40]}(...))"
    raise PolynomialError(f"not a polynomial in {names}: {what} is not allowed in a polynomial "
                          f"string. Accepted: {_SYNTAX}; or pass a sympy expression")


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


def to_sympy(poly: Polynomial):
    """A sympy expression of ``poly``; decision variables become symbols named as they print
    (:func:`.decision.decision_name`: ``g``, ``c[1]``, else ``d<id>``; ``d<id>`` when that name
    is also one of the polynomial's variables, or shared by two decision variables)."""
    import sympy                    # lazily (1 s to import): see the module docstring

    xs = [sympy.Symbol(v) for v in poly.vars]
    names = [decision_name(i) for i in poly.ids]
    clash = {n for n in names if n in poly.vars or names.count(n) > 1}
    ds = [sympy.Symbol(n if n not in clash else f"d{int(i)}") for n, i in zip(names, poly.ids)]
    expr = sympy.Integer(0)
    for i in range(poly.nterms):
        c = sympy.nsimplify(poly.coef[i, 0], rational=False) if poly.coef[i, 0] else 0
        c += sum(float(a) * d for a, d in zip(poly.coef[i, 1:], ds) if a)
        expr += c * sympy.Mul(*[x ** int(e) for x, e in zip(xs, poly.exps[i])])
    return expr

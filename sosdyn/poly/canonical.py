"""Canonical forms of a :class:`~.polynomial.Polynomial` on its arrays: variable order, identity, printing.

* Variable order of a result (:func:`merged_vars`): when one operand's variables include the
  other's, the larger tuple's order is kept; otherwise the union in natural order (``x2`` before
  ``x10``, ``x`` before ``y``). Never the operand order: ``y + x**2`` and ``x**2 + y`` both
  have vars ``("x", "y")``.
* Identity by value (:func:`canonical_key`): the variables of positive degree sorted, rows
  sorted, ``-0.0`` as ``0.0`` -- equal polynomials (``==``) have equal keys, so equal hashes.
* Printing (:func:`format_terms`): decision variables by their names (:func:`.decision.decision_name`).
"""
from __future__ import annotations

import functools
import re

import numpy as np

from .decision import decision_name


def natural_key(name: str) -> tuple:
    """Sort key with digit runs compared as numbers: x2 < x10."""
    return tuple((0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", name) if t)


def merged_vars(a: tuple, b: tuple) -> tuple:
    """Variables of a result over operands with variables ``a`` and ``b`` (module doc)."""
    return a if a == b else _merged(a, b)


@functools.lru_cache(maxsize=1024)         # a program combines the same few tuples many times
def _merged(a: tuple, b: tuple) -> tuple:
    sa, sb = set(a), set(b)
    if sa >= sb and sa != sb:
        return a
    if sb >= sa and sa != sb:
        return b
    return tuple(sorted(sa | sb, key=natural_key))


def canonical_key(vars: tuple, exps: np.ndarray, coef: np.ndarray, ids: np.ndarray) -> tuple:
    """A hashable key equal for polynomials equal by value (module doc)."""
    used = [j for j in range(len(vars)) if exps.shape[0] and exps[:, j].any()]
    order = sorted(used, key=lambda j: vars[j])
    e = exps[:, order]
    rows = np.lexsort(e.T[::-1]) if e.shape[1] else np.arange(e.shape[0])
    return (tuple(vars[j] for j in order), e[rows].tobytes(), (coef[rows] + 0.0).tobytes(), ids.tobytes())


def _number(c: float) -> str:
    return f"{c:.6g}"


def format_terms(vars: tuple, exps: np.ndarray, coef: np.ndarray, ids: np.ndarray) -> str:
    """The polynomial as text: ``2*x^2 - 3*x*y + (1 + 0.5*g)*y``; decision variables by name."""
    if not exps.shape[0]:
        return "0"
    out = ""
    for i in range(exps.shape[0]):
        mono = "*".join(v if e == 1 else f"{v}^{e}" for v, e in zip(vars, exps[i]) if e)
        parts = [(coef[i, 0], "")] if coef[i, 0] else []
        parts += [(c, decision_name(d)) for c, d in zip(coef[i, 1:], ids) if c]
        if len(parts) == 1:
            c, name = parts[0]
            sign, mag = ("-" if c < 0 else "+"), abs(c)
            factors = ([] if mag == 1 and (name or mono) else [_number(mag)]) + ([name] if name else [])
            text = "*".join(factors + ([mono] if mono else []))
        else:
            inner = " + ".join(_number(c) + (f"*{name}" if name else "") for c, name in parts)
            sign, text = "+", f"({inner})" + (f"*{mono}" if mono else "")
        out += (("-" if sign == "-" else "") + text) if not out else f" {sign} {text}"
    return out

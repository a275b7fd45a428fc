"""Polynomial layer: numeric sparse polynomials and polynomial matrices.

Everything here is exponent arrays and coefficient arrays; no solver, no sympy in the hot
path (sympy conversion is in :mod:`sosdyn.poly.sympy_io`). Modules, bottom up: ``decision``
(decision ids), ``monomials`` (exponent rows), ``evaluation`` (monomial values and
gradients at points), ``checks`` (admissible data), ``polynomial``, ``termarrays`` (polynomial
matrices as flat term arrays), ``matrix``, ``sympy_io``.
"""
from .checks import MAX_COEFFICIENT, check_terms_size, finite_points, real_array
from .decision import allocate
from .evaluation import monomial_gradients, monomial_values
from .matrix import PolyMatrix, jacobian
from .monomials import MAX_DEGREE, keys_to_exps, match_rows, monomials_up_to, multiset_keys, unique_rows
from .polynomial import Polynomial, variable_names, variables
from .sympy_io import from_sympy, to_sympy

__all__ = ["Polynomial", "PolyMatrix", "variables", "variable_names", "jacobian",
           "monomials_up_to", "match_rows", "unique_rows", "multiset_keys", "keys_to_exps",
           "monomial_values", "monomial_gradients",
           "from_sympy", "to_sympy", "allocate", "check_terms_size", "finite_points", "real_array",
           "MAX_COEFFICIENT", "MAX_DEGREE"]

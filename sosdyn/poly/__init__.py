"""Polynomial layer: numeric sparse polynomials and polynomial matrices.

Everything here is exponent arrays and coefficient arrays; no solver, no sympy in the hot
path (sympy conversion is in :mod:`sosdyn.poly.sympy_io`).
"""
from .decision import allocate
from .matrix import PolyMatrix, jacobian
from .monomials import monomials_up_to
from .polynomial import Polynomial, check_terms_size, variable_names, variables
from .sympy_io import from_sympy, to_sympy

__all__ = ["Polynomial", "PolyMatrix", "variables", "variable_names", "jacobian",
           "monomials_up_to", "from_sympy", "to_sympy", "allocate", "check_terms_size"]

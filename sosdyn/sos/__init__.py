"""SOS layer: programs, Gram bases (Newton polytope), lowering to conic form, certificates.

Modules, bottom up: ``gram`` (svec layout, coefficient matching, exact arithmetic),
``newton`` (Gram bases), ``objective``, ``constraints`` (bases, blocks, rows, constraint
handles, ``matrix_form``), ``conic`` (the standard conic form), ``verification`` (the
independent check), ``rigorous`` (proven bounds), ``moments`` and ``decomposition`` (the dual side: moments
and minimisers; an SOS written out), ``solution``, ``backends`` (solvers),
``sets`` (basic semialgebraic sets, Putinar terms), ``sparsity`` (correlative and term
sparse Gram bases), ``program`` (``SOSProgram``), ``minimize`` (``minimize_on``: verified lower
bounds), ``examples`` (textbook problems with known answers).
"""
from .backends import SOLVERS
from .constraints import (Basis, EqualityMultiplier, FamilySOSConstraint, LinearRows, Multiplier, PsdBlock,
                          SOSConstraint, matrix_form)
from .decomposition import SOSDecomposition
from .gram import svec_to_matrix
from .minimize import LowerBound, minimize_on
from .moments import Atoms, Moments
from .newton import newton_basis
from .objective import QuadraticForm, sum_squares
from .program import SOSProgram
from .rigorous import Bound
from .sets import BasicSet
from .solution import Solution
from .verification import CertificateCheck, VerificationReport, check_gram

__all__ = ["SOSProgram", "SOSConstraint", "FamilySOSConstraint", "Multiplier", "EqualityMultiplier",
           "Basis", "PsdBlock", "LinearRows", "matrix_form", "Solution", "VerificationReport",
           "CertificateCheck", "check_gram", "Bound", "QuadraticForm", "sum_squares", "newton_basis",
           "svec_to_matrix", "SOLVERS", "BasicSet", "minimize_on", "LowerBound",
           "Moments", "Atoms", "SOSDecomposition"]

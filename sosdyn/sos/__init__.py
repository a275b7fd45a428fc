"""SOS layer: programs, Gram bases (Newton polytope), lowering to conic form, certificates."""
from .gram import svec_to_matrix
from .newton import newton_basis
from .objective import QuadraticForm, sum_squares
from .program import Basis, Multiplier, SOSConstraint, SOSProgram
from .solution import Bound, CertificateCheck, Solution, VerificationReport

__all__ = ["SOSProgram", "SOSConstraint", "Multiplier", "Basis", "Solution", "VerificationReport",
           "CertificateCheck", "Bound", "QuadraticForm", "sum_squares", "newton_basis", "svec_to_matrix"]

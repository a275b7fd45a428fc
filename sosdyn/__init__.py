"""sosdyn: sum-of-squares programming and provably convergent motion learning (CDSP).

Layers: :mod:`sosdyn.poly` (numeric polynomials) -> :mod:`sosdyn.sos` (SOS programs and
their conic lowering) -> :mod:`sosdyn.lfd` (learning from demonstrations).
"""
from .errors import (DemonstrationError, InfeasibleError, InputError, ModelFileError,
                     NoAtomsError, NotCertifiedError, NotFittedError, NotSymmetricError, PolynomialError,
                     ResourceLimitError, SolverError, SosdynError, UnboundedError, UnverifiedSolutionError,
                     WorkLimitError)
from .limits import get_limits, limits, set_limits
from .poly import PolyMatrix, Polynomial, from_sympy, jacobian, to_sympy, variables
from .sos import BasicSet, SOSProgram, Solution, minimize_on, sum_squares
from .lfd import (CDSP, Demonstration, Demonstrations, PoseCDSP, PoseDemonstrations, SecondOrderCDSP, Trajectory,
                  check_demonstrations, dataset_names, lasa_names, load_dataset, load_demos, load_lasa, load_model,
                  load_pose_demos, load_pose_model, preprocess, preprocess_poses)

__version__ = "0.1.0"

__all__ = [
    "SosdynError", "InputError", "PolynomialError", "NotSymmetricError", "DemonstrationError",
    "ModelFileError", "SolverError", "InfeasibleError", "NotCertifiedError", "NotFittedError",
    "ResourceLimitError", "UnverifiedSolutionError", "UnboundedError", "NoAtomsError", "WorkLimitError", "get_limits", "set_limits", "limits",
    "Polynomial", "PolyMatrix", "variables", "jacobian", "from_sympy", "to_sympy",
    "SOSProgram", "Solution", "sum_squares", "BasicSet", "minimize_on",
    "CDSP", "Demonstration", "Demonstrations", "Trajectory", "check_demonstrations",
    "dataset_names", "lasa_names", "load_dataset", "load_demos", "load_lasa", "load_model", "preprocess",
    "PoseCDSP", "PoseDemonstrations", "load_pose_demos", "load_pose_model", "preprocess_poses", "SecondOrderCDSP",
]

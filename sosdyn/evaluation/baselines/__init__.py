"""Baseline motion models behind one interface (docs/interfaces.md, "Motion models").

``GMR`` (no guarantee), ``DMP`` (time-indexed, one per demonstration) and ``CLFDM``
(GMR + learned control Lyapunov function).  ``gmm_linear_maps`` and
``position_responsibilities`` are shared with the CDSP learner.
"""

from sosdyn.evaluation.baselines.base import AutonomousModel, MotionModel
from sosdyn.evaluation.baselines.clfdm import CLFDM, WSAQF, fit_wsaqf
from sosdyn.evaluation.baselines.dmp import DMP
from sosdyn.evaluation.baselines.gmr import GMR, gmm_linear_maps, position_responsibilities

__all__ = [
    "AutonomousModel", "CLFDM", "DMP", "GMR", "MotionModel", "WSAQF", "fit_wsaqf",
    "gmm_linear_maps", "position_responsibilities",
]

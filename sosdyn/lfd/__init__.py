"""Learning from demonstrations: data, the CDSP estimator, its convex steps, rollouts, model files."""
from .cdsp import CDSP, load_model, save_model
from .data import Demonstration, Demonstrations, check_demonstrations, lasa_names, load_demos, load_lasa
from .rollout import Trajectory, rollout

__all__ = ["CDSP", "Demonstration", "Demonstrations", "check_demonstrations", "lasa_names",
           "load_demos", "load_lasa", "load_model", "save_model", "Trajectory", "rollout"]

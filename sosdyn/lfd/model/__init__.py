"""The fitted models: the :class:`CDSP` estimator (it holds state; the maths is in ``fit``), the
pose model :class:`PoseCDSP` (``pose``), the certified second-order model :class:`SecondOrderCDSP`
(``second_order``, ``second_order_file``); the model files' content (``content``), the signed JSON
file format (``fileformat``) and loading / saving model files (``files``).
"""
from .cdsp import CDSP
from .files import load_model, load_pose_model, save_model
from .pose import PoseCDSP
from .second_order import SecondOrderCDSP

__all__ = ["CDSP", "PoseCDSP", "SecondOrderCDSP", "load_model", "load_pose_model", "save_model"]

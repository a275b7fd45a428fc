"""The fitted model: the :class:`CDSP` estimator (it holds state; the maths is in ``fit``),
its state record (``state``), the signed JSON file format (``fileformat``) and loading /
saving model files (``files``).
"""
from .cdsp import CDSP
from .files import load_model, save_model

__all__ = ["CDSP", "load_model", "save_model"]

"""Reading model files of every family: :func:`load_model` (every field validated, the certificate
re-checked) returns the family the file's ``format`` names (:func:`~.base.family_of`).

The file itself (JSON, checksum, signature, atomic writes) is :mod:`.fileformat`; its content, field
by field, :mod:`.content`; writing is :meth:`~.base.MotionModel.save` (:func:`save_model`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sosdyn.errors import ModelFileError, SosdynError
from ..fit.certificate import DEFAULT_SAMPLES
from .base import FAMILIES, MotionModel, family_of
from .cdsp import CDSP
from .content import POSE_FORMAT, TOP_LEVEL, check_fields, check_load_work
from .fileformat import REFIT_HINT, model_format, read_model_file
from .pose import PoseCDSP
from .second_order import SecondOrderCDSP

LOAD_SEED = 0                   # the states of the sampled check when loading a file


def save_model(model: MotionModel, path, key=None) -> Path:
    """``model.save(path, key)``: see :meth:`~.base.MotionModel.save`."""
    return model.save(path, key)


def load_model(path, key=None, family: type[MotionModel] | None = None) -> CDSP | PoseCDSP | SecondOrderCDSP:
    """Read a model file written by any family's ``save``: the file's checks (size, JSON, checksum,
    signature: :func:`~.fileformat.read_model_file`), its top-level fields (anything unknown refused),
    the work its checks will take (:func:`~.content.check_load_work`, before they start), every
    field (the family's ``from_content``) and the certificate, re-checked from the model's own
    coefficients (:func:`checked_model`). ``family`` (a class): refuse files of another family.

    With ``key`` (bytes or str; default $SOSDYN_MODEL_KEY) the file must carry a matching HMAC.
    The file's ``verify_samples`` and ``random_state`` do not make the check weaker. Every failure
    is a ModelFileError, or a ResourceLimitError naming the limit.
    """
    path = Path(path)
    fmt = model_format(path)
    cls = family_of(fmt) if family is None or fmt == family.file_format else None
    if cls is None:
        wanted = family.file_format if family is not None else " or ".join(FAMILIES)
        raise ModelFileError(f"{path} is not a {wanted} file (its format field is {fmt!r:.40}). Try: the JSON "
                             "written by a model's save() or `sosdyn fit`.")
    content = read_model_file(path, key, cls.file_format, cls.file_version)
    try:
        check_fields(content, ("format", "version", *TOP_LEVEL[cls.file_format]), "")
        check_load_work(cls.file_format, content)
        model = cls.from_content(content)
    except ModelFileError as exc:
        text = str(exc).rstrip(".")
        raise ModelFileError(f"{path}: {text}." + ("" if "Try:" in text else f" {REFIT_HINT}")) from None
    return checked_model(path, model)


def checked_model(path: Path, model: MotionModel) -> MotionModel:
    """``model`` with its certificate re-checked from its coefficients (DEFAULT_SAMPLES states, seed
    LOAD_SEED): ``verification_`` set and ``certified_`` True, or ModelFileError."""
    try:
        report = model.verify(DEFAULT_SAMPLES, LOAD_SEED)
    except (SosdynError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        raise ModelFileError(f"{path}: its certificate cannot be re-checked from its coefficients "
                             f"({type(exc).__name__}: {exc}); refusing to load. {REFIT_HINT}") from None
    if not report.passed:
        raise ModelFileError(f"{path}: the stored certificate does not check out; refusing to load.\n"
                             f"{report}\n{REFIT_HINT}")
    model.accept(report)
    return model


def load_pose_model(path, key=None) -> PoseCDSP:
    """:func:`load_model` of a pose model file (format ``sosdyn-pose``) only."""
    return load_model(path, key, family_of(POSE_FORMAT))


__all__ = ["LOAD_SEED", "checked_model", "load_model", "load_pose_model", "save_model"]

"""Reading model files: :func:`load_model` (every field validated, certificate re-checked), a CDSP
or, for a file whose format field is ``sosdyn-pose``, a :class:`~.pose.PoseCDSP` (:func:`load_pose_model`).

The file itself (JSON, checksum, signature, atomic writes) is :mod:`.model_io`; its state, field by
field, :mod:`.model_state`; writing is :meth:`~sosdyn.lfd.model.cdsp.CDSP.save` (:func:`save_model`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sosdyn.errors import InputError, ModelFileError, SosdynError
from .cdsp import CDSP, DEFAULTS
from ..fit.certificate import DEFAULT_SAMPLES
from ..fit.learner import Settings
from .fileformat import REFIT_HINT, model_format, read_model_file
from .pose import POSE_FORMAT, PoseCDSP
from .pose_file import load_pose_content, pose_from_content
from .second_order import SECOND_ORDER_FORMAT, SecondOrderCDSP
from .second_order_file import second_order_from_file
from .state import check_param_names, need, validate_state
from ..fit.params import LEGACY_PARAMS, PARAMS, check_params, resolve_seed

LOAD_SEED = 0                   # the states of the sampled check when loading a file


def save_model(model: CDSP, path, key=None) -> Path:
    """``model.save(path, key)``: see :meth:`~sosdyn.lfd.model.cdsp.CDSP.save`."""
    return model.save(path, key)


def load_model(path, key=None) -> CDSP | PoseCDSP | SecondOrderCDSP:
    """Read a model written by :meth:`~sosdyn.lfd.model.cdsp.CDSP.save`: every field validated,
    certificate re-checked; a pose model file (format ``sosdyn-pose``, written by
    :meth:`~.pose.PoseCDSP.save`) is read by :func:`load_pose_model`, a second-order one (format
    ``sosdyn-second-order``) by :func:`~.second_order_file.second_order_from_file` and then checked here.

    With ``key`` (bytes or str; default $SOSDYN_MODEL_KEY) the file must carry a matching HMAC.
    The certificate is re-checked from the model's own coefficients (Gram matrices, and
    DEFAULT_SAMPLES sampled states with a fixed seed; with a warp also every l_j < 1 and the
    sampled singular values of J_phi): the file's ``verify_samples`` and ``random_state`` do not
    make this check weaker. Every failure is a ModelFileError.
    """
    path = Path(path)
    kind = model_format(path)
    if kind == POSE_FORMAT:
        return load_pose_model(path, key)
    if kind == SECOND_ORDER_FORMAT:
        return checked_model(path, second_order_from_file(path, key))
    return checked_model(path, model_from_content_at(path, read_model_file(path, key)))


def model_from_content_at(path: Path, content: dict) -> CDSP:
    """:func:`model_from_content`, its ModelFileError naming ``path`` (with the refit hint)."""
    try:
        return model_from_content(content)
    except ModelFileError as exc:
        text = str(exc).rstrip(".")
        raise ModelFileError(f"{path}: {text}." + ("" if "Try:" in text else f" {REFIT_HINT}")) from None


def checked_model(path: Path, model: CDSP | SecondOrderCDSP) -> CDSP | SecondOrderCDSP:
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
    model.verification_, model.certified_ = report, True
    return model


def load_pose_model(path, key=None) -> PoseCDSP:
    """Read a file written by :meth:`PoseCDSP.save` (:mod:`.pose_file`): every field validated, each
    block loaded as a CDSP file and its certificate re-checked."""
    path = Path(path)
    return pose_from_content(path, load_pose_content(path, key),
                             lambda where, block: checked_model(where, model_from_content_at(where, block)))


def model_from_content(content: dict) -> CDSP:
    """A CDSP (not yet verified) from a file's content; ModelFileError naming the first bad field."""
    params = dict(LEGACY_PARAMS, **need(content, "params", "", dict))   # files older than a parameter
    check_param_names(params, PARAMS)
    model = CDSP(**params)
    try:
        check_params(params, DEFAULTS)
    except InputError as exc:
        raise ModelFileError(f"invalid params: {exc}") from None
    model.seed_ = resolve_seed(model.random_state)
    metric_degree = Settings.from_params(params).learned_metric_degree
    state = validate_state(need(content, "state", "", dict), model.n_components, model.field_degree,
                           metric_degree, 0.5 * model.eps)
    for name, value in state.items():
        setattr(model, name, value)
    return model


__all__ = ["LOAD_SEED", "load_model", "load_pose_model", "model_from_content", "save_model"]

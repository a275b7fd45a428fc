"""Reading a second-order model file (format ``sosdyn-second-order``, written by
:meth:`~.second_order.SecondOrderCDSP.save`): every field's shape and values checked. Then
:func:`~.files.load_model` (which dispatches here on the format field) re-checks the certificate from
the stored fields and metric (exact LMIs and DEFAULT_SAMPLES sampled states with a fixed seed,
whatever the file's ``verify_samples`` says). Every failure is a ModelFileError.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sosdyn.errors import InputError, ModelFileError
from ..fit.gmm import PositionMixture
from .fileformat import REFIT_HINT, read_model_file
from .second_order import PARAMS, SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION, SecondOrderCDSP


def _array(state: dict, name: str, shape: tuple) -> np.ndarray:
    """state[name] as a float array of ``shape`` (None entries: any size), else ModelFileError."""
    try:
        arr = np.asarray(state[name], dtype=float)
    except (KeyError, TypeError, ValueError):
        raise ModelFileError(f"state field {name!r} is missing or not numeric") from None
    if arr.ndim != len(shape) or any(w is not None and w != a for w, a in zip(shape, arr.shape)):
        raise ModelFileError(f"state field {name!r} has shape {arr.shape}, expected {shape}")
    return arr


def model_from_state(params: dict, state: dict) -> SecondOrderCDSP:
    """A SecondOrderCDSP (not yet verified) from a file's params and state; ModelFileError naming the
    first bad field."""
    if not isinstance(params, dict) or set(params) != set(PARAMS):
        raise ModelFileError(f"params must name exactly {sorted(PARAMS)}")
    model = SecondOrderCDSP(**params)
    try:
        model.check_params()
    except InputError as exc:
        raise ModelFileError(f"invalid params: {exc}") from None
    if not isinstance(state, dict):
        raise ModelFileError("state must be an object")
    goal = _array(state, "goal", (None,))
    n = goal.size
    C = _array(state, "C", (None, n, 2 * n))
    K = C.shape[0]
    M = _array(state, "M", (2 * n, 2 * n))
    weights = _array(state, "weights", (K,))
    means, covs = _array(state, "means", (K, 2 * n)), _array(state, "covariances", (K, 2 * n, 2 * n))
    scalars = {name: float(_array(state, name, ())) for name in ("dt", "length_scale", "time_scale", "margin")}
    if n < 1 or any(not v > 0 for v in scalars.values()) or not (weights > 0).all():
        raise ModelFileError("dt, length_scale, time_scale, margin and the mixture weights must be > 0")
    if any(np.linalg.eigvalsh(0.5 * (S + S.T))[0] <= 0 for S in covs):
        raise ModelFileError("a gating covariance is not positive definite")
    model.seed_, model.dim_, model.goal_, model.dt_ = int(params["random_state"]), n, goal, scalars["dt"]
    model.length_scale_, model.time_scale_ = scalars["length_scale"], scalars["time_scale"]
    model.margin_ = scalars["margin"]
    model.window_ = int(_array(state, "window", ()))
    model.mixture_ = PositionMixture(weights / weights.sum(), means, covs)
    model.C_, model.M_, model.history_ = C, M, []
    return model


def second_order_from_file(path, key=None) -> SecondOrderCDSP:
    """The (not yet verified) model in ``path``: file checks and every field, or ModelFileError
    naming ``path``; :func:`~.files.load_model` then re-checks its certificate."""
    path = Path(path)
    content = read_model_file(path, key, SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION)
    try:
        return model_from_state(content.get("params"), content.get("state"))
    except ModelFileError as exc:
        raise ModelFileError(f"{path}: {exc}. {REFIT_HINT}") from None


__all__ = ["model_from_state", "second_order_from_file"]

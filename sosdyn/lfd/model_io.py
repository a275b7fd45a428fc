"""Model files: plain JSON (no pickle), checksummed, re-verified on load.

A file holds the hyper-parameters, the learned arrays (as lists of floats, exact under JSON
round trips), the certificate's Gram matrices and a SHA-256 checksum of all of it. Loading
refuses a file that does not parse, has another format/version, whose checksum does not
match (edited or corrupt), or whose certificate fails the independent check.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from ..errors import ModelFileError, SosdynError
from .gmm import PositionMixture

FORMAT, VERSION = "sosdyn-cdsp", 1
_ARRAYS = ("goal_", "C_", "W_", "field_exps_", "metric_exps_")


def _payload(model) -> dict:
    m = model.mixture_
    return {
        "format": FORMAT, "version": VERSION, "params": model.get_params(),
        "state": {
            "dim_": model.dim_, "scale_": model.scale_, "dt_": model.dt_, "units_": model.units_,
            "n_components_": model.n_components_,
            "gmr_cost_": model.gmr_cost_,
            **{k: np.asarray(getattr(model, k)).tolist() for k in _ARRAYS},
            "mixture_": {"weights": m.weights.tolist(), "means": m.means.tolist(),
                         "covariances": m.covariances.tolist()},
            "certificate_": model.certificate_, "history_": model.history_,
            "metric_collapse_": model.metric_collapse_, "timings_": model.timings_,
        },
    }


def _digest(payload: dict) -> str:
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def save_model(model, path) -> Path:
    """Write ``model`` to ``path`` (JSON)."""
    model._check_fitted()
    payload = _payload(model)
    payload["sha256"] = _digest(payload)
    path = Path(path)
    path.write_text(json.dumps(payload, sort_keys=True, indent=1) + "\n")
    return path


def load_model(path):
    """Read a model file written by :func:`save_model`; re-runs the certificate check."""
    from .cdsp import CDSP

    path = Path(path)
    try:
        payload = json.loads(path.read_text())
    except FileNotFoundError:
        raise ModelFileError(f"no model file at {path}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ModelFileError(f"{path} is not a sosdyn model file (corrupt or truncated JSON: {exc})") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ModelFileError(f"{path} is not a {FORMAT} file")
    if payload.get("version") != VERSION:
        raise ModelFileError(f"{path} has format version {payload.get('version')!r}; this sosdyn reads {VERSION}")
    digest = payload.pop("sha256", None)
    if digest != _digest(payload):
        raise ModelFileError(f"{path} fails its checksum: the file was edited or corrupted; refit the model")
    try:
        model = CDSP(**payload["params"])
        st = payload["state"]
        for k in ("dim_", "scale_", "dt_", "units_", "n_components_", "gmr_cost_", "certificate_", "history_",
                  "metric_collapse_", "timings_"):
            setattr(model, k, st[k])
        model.goal_ = np.asarray(st["goal_"], dtype=float)
        model.C_ = np.asarray(st["C_"], dtype=float)
        model.W_ = np.asarray(st["W_"], dtype=float)
        model.field_exps_ = np.asarray(st["field_exps_"], dtype=np.int64).reshape(-1, model.dim_)
        model.metric_exps_ = np.asarray(st["metric_exps_"], dtype=np.int64).reshape(-1, model.dim_)
        mx = st["mixture_"]
        model.mixture_ = PositionMixture(np.asarray(mx["weights"], dtype=float),
                                         np.asarray(mx["means"], dtype=float),
                                         np.asarray(mx["covariances"], dtype=float))
        model.verification_ = model.verify()
    except SosdynError:
        raise
    except (KeyError, TypeError, ValueError, np.linalg.LinAlgError) as exc:
        raise ModelFileError(f"{path} is malformed ({type(exc).__name__}: {exc})") from None
    if not model.verification_.passed:
        raise ModelFileError(f"{path}: the stored certificate does not check out; refusing to load.\n"
                             f"{model.verification_}")
    model.certified_ = True
    return model

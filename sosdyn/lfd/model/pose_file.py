"""Reading a pose model file (format ``sosdyn-pose``, written by :meth:`~.pose.PoseCDSP.save`).

The file holds ``goal_tol_deg``, ``goal_quat`` (w x y z), ``still`` ({"position", "orientation"}: null or
the rate of a block that did not move) and the two blocks ``position`` and ``orientation``, each the
``params`` and ``state`` of a CDSP file. Every field is validated (numbers where numbers are required, no
null, no unknown field), each block is loaded as a CDSP file is (:func:`~.files.model_from_content`) and its
certificate re-checked from its coefficients; the orientation block must be the identity-metric CDSP with
goal r = 0 and no warp that the angle argument needs (docs/theory.md, "Poses"). Every failure is a
:class:`~sosdyn.errors.ModelFileError` naming the field.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sosdyn.errors import ModelFileError
from .fileformat import REFIT_HINT, read_model_file
from .cdsp import DEFAULTS
from .pose import BLOCKS, POSE_FORMAT, POSE_VERSION, PoseCDSP
from .reach import metric_matrix
from .state import array, need, positive

POSE_FIELDS = {"format", "version", "goal_tol_deg", "goal_quat", "still", *BLOCKS}


def _fail(path: Path, text: str):
    raise ModelFileError(f"{path}: {text}. {REFIT_HINT}")


def pose_from_content(path: Path, content: dict, load_block) -> PoseCDSP:
    """A PoseCDSP from a pose file's ``content``; ``load_block(path, block_content)`` reads and re-checks
    one block (a CDSP)."""
    unknown = sorted(set(content) - POSE_FIELDS)
    if unknown:
        _fail(path, f"unknown fields {unknown} (a pose model file holds {sorted(POSE_FIELDS)})")
    try:
        tol = positive(need(content, "goal_tol_deg", ""), "goal_tol_deg")
        q = array(need(content, "goal_quat", ""), "goal_quat", (4,))
        still = need(content, "still", "", dict)
        if set(still) != set(BLOCKS):
            raise ModelFileError(f"malformed: still must have exactly the fields {list(BLOCKS)}")
        rates = {b: None if still[b] is None else positive(still[b], f"still.{b}") for b in BLOCKS}
    except ModelFileError as exc:
        _fail(path, str(exc))
    if not tol < 180:
        _fail(path, f"goal_tol_deg = {tol!r} is not in (0, 180)")
    if not math.isclose(np.linalg.norm(q), 1.0, abs_tol=1e-9):
        _fail(path, f"goal_quat {q} is not a unit quaternion")
    blocks = {b: load_block(path, need(content, b, "", dict)) for b in BLOCKS}
    params = {k: v for k, v in blocks["position"].get_params().items()
              if k != "progress" and not (v is DEFAULTS[k] or v == DEFAULTS[k])}
    model = PoseCDSP(tol, **params)
    model.position_, model.orientation_ = blocks["position"], blocks["orientation"]
    ori = model.orientation_
    M = metric_matrix(ori)
    if ori.metric != "identity" or ori.warp_ is not None or ori.dim_ != 3 or model.position_.dim_ != 3 or M is None or \
            not np.array_equal(M, M[0, 0] * np.eye(3)) or np.any(ori.goal_ != 0.0):
        _fail(path, "the orientation block must be a 3-D CDSP with the identity metric, no warp and goal 0 "
                    "(the angle to the goal orientation then never increases), and the position block 3-D")
    model.goal_quat_, model.still_ = q / np.linalg.norm(q), rates
    return model


def load_pose_content(path, key=None) -> dict:
    """The checked JSON content of a pose model file (format, version, digests: :func:`read_model_file`)."""
    return read_model_file(Path(path), key, POSE_FORMAT, POSE_VERSION)

"""The two blocks of a pose model and what each is fitted on (docs/theory.md, "Poses").

* Position: a :class:`~sosdyn.lfd.model.cdsp.CDSP` of the positions x, with the parameters as given
  (the position models' defaults, warp and gating included).
* Orientation: a CDSP of the rotation vector r = log(R_g^T R) with goal r = 0 and the parameters
  :func:`orientation_params`: the identity metric (``metric="identity"``, degree 0) and no warp, so
  its certificate J_k(r) + J_k(r)^T <= -gamma I (every k, every r) gives
  d|r|^2/dt = 2 sum_k h_k r^T f_k(r) <= -gamma |r|^2: the geodesic angle |r| to the goal never
  increases (a warp would certify the metric J_phi^T J_phi, not the angle); no corrective rounds; the
  tempered gating unless another is asked for (starts far from the demonstrated orientations, e.g. 170 deg
  off, are common for a gripper: the posterior gating switched there, a jump of 0.2 rad/s in |omega| in
  5 ms on openbox; tempered: 0.005).
  Its gating is on r (the position carried no information the orientation field could use: a gating
  on (x, r) or x was measured no better on the robottasks demos, docs/theory.md).

A block that does not move in the demonstrations has nothing to learn (:func:`still_block`): positions
whose bounding-box diagonal is at most STILL_RELATIVE of their magnitude (a pure rotation in place) or
orientations within STILL_ANGLE rad of the goal (a gripper that keeps its orientation). Its CDSP is
fitted on :func:`isotropic_demonstrations` of e(t) = e0 exp(-a t), a = STILL_RATE / (the demos' median
duration): the block returns to its goal if pushed, at the rate declared in the model (``still_``),
and nothing is scaled by round-off.
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import DemonstrationError
from ..data.demonstrations import Demonstration, Demonstrations

STILL_RELATIVE = 1e-9        # positions spreading less than this x their magnitude do not move
STILL_ANGLE = 1e-6           # rad: orientations all within this of the goal do not move
STILL_RATE = 3.0             # a still block returns to its goal at a = STILL_RATE / duration (95 % in one)
STILL_SAMPLES = 400          # samples of each synthetic demonstration of a still block
ORIENTATION_FIXED = {"metric": "identity", "metric_degree": 0, "warp": "none", "corrective_rounds": 0}
ORIENTATION_DEFAULTS = {"gating": "tempered"}


def orientation_params(params: dict) -> dict:
    """The orientation CDSP's parameters: ORIENTATION_DEFAULTS, then ``params``, then ORIENTATION_FIXED
    (module docstring)."""
    return {**ORIENTATION_DEFAULTS, **params, **ORIENTATION_FIXED}


def still_block(demos: Demonstrations, kind: str) -> float | None:
    """a = STILL_RATE / (median duration) if the samples of ``demos`` do not move (``kind``:
    "position" or "orientation", module docstring), else None."""
    X = np.vstack([d.pos for d in demos])
    if kind == "orientation":
        still = np.linalg.norm(X, axis=1).max() <= STILL_ANGLE
    else:
        still = np.linalg.norm(X.max(axis=0) - X.min(axis=0)) <= STILL_RELATIVE * np.abs(X).max()
    return STILL_RATE / float(np.median([d.duration for d in demos])) if still else None


def isotropic_demonstrations(dim: int, rate: float, goal, units: str, name: str) -> Demonstrations:
    """2 dim demonstrations of e(t) = e0 exp(-rate t) from e0 = +-unit vectors around ``goal``, over
    10 / rate s (ends within 5e-5 of the goal), STILL_SAMPLES samples each."""
    t = np.linspace(0.0, 10.0 / rate, STILL_SAMPLES)
    decay = np.exp(-rate * t)[:, None]
    starts = np.vstack([np.eye(dim), -np.eye(dim)])
    return Demonstrations([Demonstration(t, goal + decay * e, -rate * decay * e, f"{name}: still, e{i}")
                           for i, e in enumerate(starts)], name, units)


def check_moves(position_rate, orientation_rate, name: str) -> None:
    """DemonstrationError when neither block moves: there is no motion to learn."""
    if position_rate is not None and orientation_rate is not None:
        raise DemonstrationError(f"the pose demonstrations {name!r} never move: positions and orientations are "
                                 "constant. Try: demonstrations of a motion (or check the columns read).")

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
  Its rate, unless ``gamma`` is given: gamma = ORIENTATION_GAMMA / T (T the demos' median duration),
  so the certificate alone shrinks the angle by at least exp(-gamma T / 2) = 0.78 over a demonstration's
  duration. A rate fixed in 1/s (0.1, the position models') forced 0.45 on the 16-s robottasks
  demos, whose plates hold their orientation (the angle even rises by 5 deg) for the first 3 s: held-out
  orientation DTW 1.80x copying the nearest demo, 1.45x with the rate of T (docs/theory.md, "Poses").
  Its speed floor, unless ``speed_floor`` is given (:func:`settle_floor`): a settle zone, the floor
  only within goal_tol_deg of the goal, where every demonstration ended somewhere else and was turned
  onto the goal (the demos say nothing of the last degrees), at the least rate with which the
  reproductions, and starts on the zone's edge in every direction, arrive in time; a time change, so
  the paths and the certificate are those of the field.

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
from .floor import BOOST, floor_choice, floor_steps

STILL_RELATIVE = 1e-9        # positions spreading less than this x their magnitude do not move
STILL_ANGLE = 1e-6           # rad: orientations all within this of the goal do not move
STILL_RATE = 3.0             # a still block returns to its goal at a = STILL_RATE / duration (95 % in one)
STILL_SAMPLES = 400          # samples of each synthetic demonstration of a still block
ORIENTATION_FIXED = {"metric": "identity", "metric_degree": 0, "warp": "none", "corrective_rounds": 0}
ORIENTATION_DEFAULTS = {"gating": "tempered"}
ORIENTATION_GAMMA = 0.5      # the orientation's certified rate, x 1 / (the demos' median duration)


def orientation_params(params: dict, duration: float) -> dict:
    """The orientation CDSP's parameters (module docstring): ORIENTATION_DEFAULTS and the rate
    ORIENTATION_GAMMA / ``duration``, then ``params``, then ORIENTATION_FIXED; its speed floor "none" where
    ``params`` leave it "auto" (:func:`settle_floor` then chooses one)."""
    out = {**ORIENTATION_DEFAULTS, "gamma": ORIENTATION_GAMMA / duration, **params, **ORIENTATION_FIXED}
    return {**out, "speed_floor": "none"} if settles(params) else out


def settles(params: dict) -> bool:
    """Whether the orientation block gets a settle zone: ``params`` leave its speed floor "auto"."""
    return params.get("speed_floor", "auto") == "auto"


def settle_floor(field, demos: Demonstrations, radius: float) -> tuple[dict | None, dict[str, float]]:
    """The orientation block's settle zone (module docstring): (its ``floor_`` {"rate", "boost", "radius"}
    or None, each candidate's worst arrival ratio) for the field ``field`` (r -> rdot) on the rotation
    vectors ``demos`` (goal 0): :func:`~.floor.floor_choice` within ``radius`` (rad) of the goal, the least
    rate with which the reproductions of the demos arrive within ARRIVAL x their duration and starts on
    the zone's edge, in the 14 directions of :func:`edge_directions`, within ARRIVAL x the demos' median
    settling time (from first entering the zone to their end)."""
    edge = radius * edge_directions()
    settle = float(np.median([d.duration - d.t[np.argmax(np.linalg.norm(d.pos, axis=1) < radius)] + d.t[0]
                              for d in demos]))
    starts = np.vstack([[d.pos[0] for d in demos], edge])
    durations = [d.duration for d in demos] + [settle] * len(edge)
    rate, arrivals = floor_choice(field, np.zeros(3), demos, starts, durations, radius)
    return (None if rate is None else {"rate": rate, "boost": BOOST, "radius": float(radius)}), arrivals


def check_settle_size(demos: Demonstrations) -> None:
    """:func:`settle_floor`'s rollouts (the demos' starts and the zone's edge starts) checked against
    max_rollout_steps before any fit (ResourceLimitError with the remedies)."""
    floor_steps(demos, len(demos) + len(edge_directions()))


def edge_directions() -> np.ndarray:
    """The 14 unit vectors +-e_i and (+-1, +-1, +-1) / sqrt(3)."""
    corners = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) / np.sqrt(3.0)
    return np.vstack([np.eye(3), -np.eye(3), corners])


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

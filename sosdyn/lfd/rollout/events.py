"""What every integrator shares: the trajectory record, input checks, grid size and events.

Events are pairs ``(time, vector)``: a push ``(time, dx)`` makes the state jump
``x -> x + dx``; a goal change ``(time, new_goal)`` makes the field use ``new_goal`` from
``time`` on. :func:`parse_events` validates both lists and orders them by time, goal
changes before pushes at equal times.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from sosdyn.errors import InputError, WorkLimitError
from sosdyn.limits import check_bytes, check_count, env_name, get_limits

Field = Callable[[np.ndarray, np.ndarray], np.ndarray]  # field(X (m, n), goal (n,)) -> Xdot (m, n)

SIZE_HINT = "a larger dt or a shorter duration"


@dataclass
class Trajectory:
    """A rollout sampled on a uniform grid.

    ``t`` (T,) s from 0 to the duration; ``pos`` (T, n); ``goal_history`` (T, n) the goal in
    effect at each sample; ``events``: one dict per applied event, in time order, with keys
    ``kind`` ("push" or "goal_change"), ``time`` and ``before`` / ``after`` (the state for
    a push, the goal for a goal change). ``vel`` (T, n): the velocities of a second-order rollout
    (its state is (x, v): a push's ``before`` / ``after`` are then (2n,)), None for first order.
    """

    t: np.ndarray
    pos: np.ndarray
    goal_history: np.ndarray
    events: list[dict] = field(default_factory=list)
    vel: np.ndarray | None = None

    @property
    def states(self) -> np.ndarray:
        """The rows a model's rollout reports (the positions; a pose rollout adds its quaternions)."""
        return self.pos


def as_vector(value, n: int | None, what: str) -> np.ndarray:
    """``value`` as a finite float vector (of shape (n,) unless n is None); InputError otherwise."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be a numeric vector ({exc}).") from exc
    if arr.ndim != 1 or (n is not None and arr.shape != (n,)):
        expected = "a 1-D vector" if n is None else f"shape ({n},)"
        raise InputError(f"{what} has shape {arr.shape}; expected {expected}.")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what} contains NaN or inf: {arr}.")
    return arr


def is_positive_number(value) -> bool:
    """Whether ``value`` is a real number (Python or numpy, not a bool) in (0, inf)."""
    real = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
    return bool(real and 0 < value < np.inf)


def as_positive(value, what: str) -> float:
    """``value`` as a float in (0, inf); bools, None and strings are refused (InputError)."""
    if not is_positive_number(value):
        raise InputError(f"{what} must be a finite number > 0 (not a bool, not None), got {value!r}.")
    return float(value)


def check_rollout_size(duration: float, dt: float, dim: int, starts: int = 1) -> int:
    """Samples per rollout, round(duration / dt) + 1, after checking it against the limits.

    Counted: ``starts`` rollouts of that many samples against ``max_rollout_steps``; their
    arrays -- time grid and solver output times (2 per sample), positions, goal history and
    solver output ((3 dim) per sample), 8 bytes each -- against ``max_bytes``. Raises
    :class:`~sosdyn.errors.ResourceLimitError` before anything is allocated.
    """
    samples = duration / dt + 1.0          # a float: inf when the ratio overflows, no int overflow
    times = f" x {starts} starts" if starts > 1 else ""
    what = f"the rollout grid (duration {duration:g} s / dt {dt:g} s{times})"
    check_count(samples * starts, "max_rollout_steps", f"{what} sample count", SIZE_HINT)
    check_bytes(samples * starts * (3 * dim + 2) * 8.0, f"{what} arrays", SIZE_HINT)
    return int(round(duration / dt)) + 1


class WorkMeter:
    """The work of one integration -- field calls and wall-clock seconds -- against the limits
    ``max_rollout_calls`` and ``max_rollout_seconds`` (:mod:`sosdyn.limits`, read when the meter is
    made); remembers how far the integration got (the latest time and state the field was asked for).

    It also watches for a discontinuous field (:meth:`seen`): two consecutive calls at states less than
    JUMP_DISTANCE x |x - goal| apart whose velocities point more than JUMP_ANGLE_DEG apart. A Lipschitz
    field never does that (its direction turns by about L |dx| / |f|); a field that switches between
    sub-systems across a surface does, and a trajectory sliding along the surface makes an adaptive
    integrator crawl (a posterior-gated CDSP from 1e4 data scales: 4.4 s of 60 in 8,000 calls, every one
    a jump). After MAX_JUMPS jumps, while the pace so far (calls / t x duration) would spend more than
    CRAWL_SHARE of ``max_rollout_calls`` on the whole duration, the rollout stops with a WorkLimitError
    saying so; a switched field whose sliding costs little (CLF-DM's correction surface: 4,416 calls for
    5.8 s of 6.3 on LASA BendedLine) goes on."""

    JUMP_DISTANCE, JUMP_ANGLE_DEG, MAX_JUMPS, CRAWL_SHARE = 1e-6, 10.0, 1000, 0.25

    def __init__(self, duration: float):
        lim = get_limits()
        self.max_calls, self.max_seconds, self.duration = lim.max_rollout_calls, lim.max_rollout_seconds, duration
        self.calls, self.start, self.t, self.x = 0, time.perf_counter(), 0.0, None
        self.jumps, self._last = 0, None

    def tick(self, t: float, X: np.ndarray, goal: np.ndarray) -> None:
        """Count one field call at time ``t`` and states ``X`` (m, n); WorkLimitError over a limit."""
        self.calls += 1
        if t >= self.t or self.x is None:
            self.t, self.x = float(t), np.array(X[0])
        seconds = time.perf_counter() - self.start
        if self.calls > self.max_calls or seconds > self.max_seconds:
            raise self._stopped(goal, seconds, f"over max_rollout_calls = {self.max_calls} or max_rollout_seconds = "
                                f"{self.max_seconds}.",
                                "a start nearer the data or a shorter duration; or raise the limits, e.g. "
                                "sosdyn.set_limits(max_rollout_calls=10**6, max_rollout_seconds=3600) (the sosdyn "
                                f"command: {env_name('max_rollout_calls')}=... and {env_name('max_rollout_seconds')}=... "
                                "in the environment).")

    def seen(self, x: np.ndarray, v: np.ndarray, goal: np.ndarray) -> None:
        """The field's value ``v`` at the state ``x`` (the first of a call); counts the jumps of the class
        docstring, WorkLimitError after MAX_JUMPS of them at a crawling pace."""
        last, self._last = self._last, (np.array(x, dtype=float), np.array(v, dtype=float))
        if last is None:
            return
        near = np.linalg.norm(x - last[0]) <= self.JUMP_DISTANCE * np.linalg.norm(x - goal)
        norms = np.linalg.norm(v) * np.linalg.norm(last[1])
        if near and norms > 0 and np.dot(v, last[1]) < np.cos(np.radians(self.JUMP_ANGLE_DEG)) * norms:
            self.jumps += 1
            pace = self.calls * self.duration / max(self.t, 1e-300 * self.duration)    # calls at this pace
            if self.jumps >= self.MAX_JUMPS and pace > self.CRAWL_SHARE * self.max_calls:
                raise self._stopped(
                    goal, time.perf_counter() - self.start,
                    f"the field is discontinuous there: {self.jumps} times its direction turned by more than "
                    f"{self.JUMP_ANGLE_DEG:g} deg between states less than {self.JUMP_DISTANCE:g} x their distance "
                    "to the goal apart -- a surface across which it switches between sub-systems (a "
                    "posterior-gated CDSP far from the data, where the weights switch within a hair's width), "
                    "along which the trajectory slides and the integrator crawls.",
                    "a start nearer the data; or a model that is smooth off the data, gating='tempered' (sosdyn "
                    "fit --gating tempered: from 1e6 data scales, 1,200 to 1,900 field calls to the goal).")

    def _stopped(self, goal, seconds: float, why: str, hint: str) -> WorkLimitError:
        dist = float(np.linalg.norm(self.x - goal))
        return WorkLimitError(
            f"The rollout was stopped after {self.calls} field calls and {seconds:.3g} s, at t = {self.t:.4g} of "
            f"{self.duration:g} s, x = {self.x} ({dist:.3g} from the goal): {why}", hint,
            t=self.t, x=self.x, calls=self.calls, seconds=seconds)


def _event_list(items, n: int, duration: float, kind: str) -> list[tuple[float, str, np.ndarray]]:
    """Validate ``[(time, vector)]`` into ``[(time, kind, vector)]``."""
    if isinstance(items, (str, bytes, dict)) or not hasattr(items, "__iter__"):
        raise InputError(f"{kind} events must be a list of pairs (time, vector), got {type(items).__name__}.")
    out = []
    for i, item in enumerate(items):
        try:
            time, vector = item
        except (TypeError, ValueError) as exc:
            raise InputError(f"{kind} {i} must be a pair (time, vector), got {item!r}.") from exc
        is_number = isinstance(time, (int, float, np.number)) and not isinstance(time, bool)
        if not is_number or not 0 <= time <= duration:
            raise InputError(f"{kind} {i} time {time!r} is not inside [0, duration = {duration:g}].")
        out.append((float(time), kind, as_vector(vector, n, f"{kind} {i} vector")))
    return out


def parse_events(perturbations, goal_changes, n: int, duration: float) -> list[tuple[float, str, np.ndarray]]:
    """Pushes ``[(time, dx)]`` and goal changes ``[(time, new_goal)]`` as one time-ordered list
    of ``(time, kind, vector)``, kind "push" or "goal_change"; at equal times goal changes
    come first (a stable sort). Times must lie in [0, duration], vectors have shape (n,) and
    are finite; InputError otherwise."""
    events = _event_list(goal_changes, n, duration, "goal_change") + _event_list(perturbations, n, duration, "push")
    events.sort(key=lambda e: e[0])
    return events


def lifted(items, n: int, kind: str, sizes: tuple, size: int) -> list:
    """``[(time, vector)]`` with vectors of a length in ``sizes`` (n: position, 2n: position and
    velocity), padded with zeros to a state of ``size`` numbers, such as a second-order model's (x, v, b);
    InputError naming a bad pair (times are checked by the integrator's :func:`parse_events`)."""
    try:
        pairs = [(t, as_vector(v, None, f"{kind} {i} vector")) for i, (t, v) in enumerate(items)]
    except InputError:
        raise
    except (TypeError, ValueError):
        raise InputError(f"{kind}s must be a list of pairs (time, vector), got {items!r}.") from None
    bad = [i for i, (_, v) in enumerate(pairs) if v.size not in sizes]
    if bad:
        raise InputError(f"{kind} {bad[0]} vector has {pairs[bad[0]][1].size} entries; expected "
                         + (f"{n} (position) or {2 * n} (position and velocity)." if len(sizes) > 1 else f"{n}."))
    return [(t, np.concatenate([v, np.zeros(size - v.size)])) for t, v in pairs]

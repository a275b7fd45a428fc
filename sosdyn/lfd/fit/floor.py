"""The speed floor of a fitted field: a time change that keeps the certificate (issue 36.5).

Where demonstrations go in and out near the goal (the real pourings: down to the glass, up while
pouring, down to the goal) the averaged field nearly cancels, and reproductions crawl there: 16 of
the 63 pourings did not reach the goal in twice their demonstration's duration. The floor speeds
such places up without moving a single path:

    xdot = sigma(x) f(x),   sigma(x) = min(BOOST, max(1, kappa |x - x*| / |f(x)|))   (sigma = 1 at x*),

i.e. the model moves at least at the relative speed kappa (1/s) towards its goal, at most BOOST
times faster than f, never slower than f. A floor may act only near the goal (``radius`` rho, the
*settle zone*): kappa is then kappa fade(|x - x*| / rho), fade = 1 up to rho / 2, 0 from rho on, the
smoothstep between (:func:`fade`, C^1); sigma stays in [1, BOOST], so the theorem below holds as it is.
The pose models' orientation block settles so (:mod:`.pose`): its field is slow only in the last few
degrees, where every demonstration ended somewhere else and was turned onto the goal.

*Theorem (time change).* For any sigma(x) in [1, B] the certificate's conclusions hold for
sigma f: (i) every trajectory of sigma f is a trajectory of f traversed with the clock
dt' = sigma(x(t)) dt (the same set of points; so the reach box and the excursion bound, which bound
the points, are unchanged); (ii) the virtual system ydot = sigma(x) sum_k h_k(x) f_k(y) has the
non-negative weights sigma h_k, whose sum sigma >= 1, so the certified -G_k >= 0 (rate gamma, any
weights in the simplex) gives d/dt |dy|^2_M <= -gamma sigma |dy|^2_M <= -gamma |dy|^2_M: contraction
at rate at least gamma, and every trajectory converges to the goal. Nothing of the certificate is
re-checked: it never involved the weights' sum beyond its being positive.

*Choice* (training data only, :func:`floor_choice`): no floor when every reproduction of a
training demonstration from its first sample reaches the goal (within GOAL_FRACTION of the data's
diagonal) within ARRIVAL times the demonstration's duration; else the least kappa among the
RATE_QUANTILES of the training samples' relative speeds |xdot| / |x - x*| (samples nearer the goal
than GOAL_FRACTION of the diagonal left out) that makes them all arrive so, or the largest if none
does. The least: a floor raises accelerations (kappa^2 |x - x*|
where it binds), so it is used only where the field is too slow for the demonstrations' pace.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sosdyn.limits import check_count
from ..data.demonstrations import Demonstrations, sample_step
from ..rollout import euler_arrival_times
from ..rollout.quality import GOAL_FRACTION

BOOST = 10.0                    # the floor speeds the field up at most this many times
ARRIVAL = 1.5                   # training reproductions must reach the goal within this x their duration
RATE_QUANTILES = (0.25, 0.5, 0.75, 0.9)     # kappa candidates: these quantiles of the relative speeds


def relative_speeds(X: np.ndarray, Xdot: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """|xdot_i| / |x_i - x*| over the samples farther than GOAL_FRACTION of the diagonal from the goal."""
    r = np.linalg.norm(X - goal, axis=1)
    far = r > GOAL_FRACTION * float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    return np.linalg.norm(Xdot[far], axis=1) / r[far]


def fade(u):
    """The settle zone's weight at u = |x - x*| / rho (array or float): 1 for u <= 1/2, 0 for u >= 1,
    3 s^2 - 2 s^3 of s = 2 (1 - u) between (continuous with its derivative)."""
    s = np.clip(2.0 * (1.0 - u), 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def floor_terms(floor: dict) -> tuple[float, float, float]:
    """(kappa, B, rho) of a model's ``floor_`` ({"rate", "boost"} and, for a settle zone, "radius"; rho =
    inf: everywhere)."""
    radius = floor.get("radius")
    return float(floor["rate"]), float(floor["boost"]), np.inf if radius is None else float(radius)


def describe(floor: dict, zone: str = "") -> str:
    """One line for a model's summary: the floor's rate and factor cap; ``zone``: how the caller writes its
    settle zone's radius (in its own units), e.g. "20 deg"."""
    within = f", within {zone} of it (settle zone)" if zone else ""
    return (f"speed floor: at least {floor['rate']:.3g}/s x the distance to the goal{within}, at most "
            f"{floor['boost']:g}x the field's speed (a time change: same paths, same certificate)")


def floored(D: np.ndarray, V: np.ndarray, rate, boost=BOOST, radius=np.inf) -> np.ndarray:
    """sigma V at the rows of D = x - x* and V = f(x) (module docstring; any consistent units): ``rate``
    kappa, ``boost`` B and ``radius`` rho numbers or columns (k, 1) of per-row values (rate 0: no floor;
    rho = inf: everywhere)."""
    speed = np.hypot.reduce(V, axis=1, keepdims=True)          # hypot: no overflow where |v|^2 would
    dist = np.hypot.reduce(D, axis=1, keepdims=True)
    want = rate * fade(dist / radius) * dist
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma = np.where(speed > 0, np.minimum(boost, np.maximum(1.0, want / speed)), np.where(want > 0, boost, 1.0))
    return V * sigma


def floor_steps(demos: Demonstrations, n_starts: int | None = None) -> int:
    """The Euler steps of :func:`floor_choice`'s rollouts, ARRIVAL x the longest duration at the data's
    step (+ 2), checked for all ``n_starts`` starts (default len(demos)) against max_rollout_steps before
    any fit (ResourceLimitError whose hint names what a CDSP user can change)."""
    steps = int(np.ceil(ARRIVAL * max(d.duration for d in demos) / sample_step(demos))) + 2
    n, what = (len(demos), "demonstrations") if n_starts is None else (n_starts, "starts")
    check_count(steps * n, "max_rollout_steps",
                f"The rollouts that choose speed_floor='auto' ({n} {what} x {steps} steps, "
                f"{ARRIVAL:g}x the longest duration)", "fewer samples per demonstration (demos.subsample(k)), or "
                "speed_floor='none' or a rate (no choosing rollouts)")
    return steps


def floor_choice(field: Callable[[np.ndarray], np.ndarray], goal: np.ndarray, demos: Demonstrations,
                 starts=None, durations=None, radius: float = np.inf) -> tuple[float | None, dict[str, float]]:
    """(kappa or None, {candidate tried: worst arrival ratio, inf beyond ARRIVAL}) for the field ``field``
    (x -> xdot, data units) with goal ``goal`` (module docstring). Rollouts by explicit Euler at the
    data's step (:func:`~sosdyn.lfd.rollout.euler_arrival_times`, each stopped once it has arrived
    within GOAL_FRACTION of the diagonal or is overdue) from the demonstrations' first samples (their
    durations), or from ``starts`` (k, n) each to arrive within ARRIVAL x ``durations`` (k,); the
    candidates in increasing kappa: "none" alone first (the common case: the field arrives), then the
    others in one loop. ``radius``: the floor's settle zone (inf: everywhere)."""
    X, Xdot = demos.stacked()
    rates = relative_speeds(X, Xdot, goal)
    candidates = {"none": 0.0} if rates.size == 0 else \
        {"none": 0.0, **{f"q{round(100 * q)}": float(np.quantile(rates, q)) for q in RATE_QUANTILES}}
    floor_steps(demos, None if starts is None else len(starts))
    starts = np.array([d.pos[0] for d in demos]) if starts is None else np.asarray(starts, dtype=float)
    durations = np.array([d.duration for d in demos] if durations is None else durations, dtype=float)
    near = GOAL_FRACTION * float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    m = len(starts)

    def worst(kappas: list[float]) -> np.ndarray:
        rate = np.repeat(kappas, m)[:, None]
        times = euler_arrival_times(lambda Xb, rows: floored(Xb - goal, field(Xb), rate[rows], BOOST, radius),
                                    np.tile(starts, (len(kappas), 1)), goal, near, np.tile(ARRIVAL * durations, len(kappas)),
                                    dt=sample_step(demos))
        ratios = (times / np.tile(durations, len(kappas))).reshape(len(kappas), m).max(axis=1)
        return np.where(ratios <= ARRIVAL, ratios, np.inf)

    names = list(candidates)
    tried = dict(zip(names[:1], worst([0.0]).tolist()))
    if tried["none"] > ARRIVAL and len(names) > 1:
        tried.update(zip(names[1:], worst([candidates[k] for k in names[1:]]).tolist()))
    ok = [name for name in tried if tried[name] <= ARRIVAL]
    return (candidates[ok[0] if ok else names[-1]] or None), tried


__all__ = ["ARRIVAL", "BOOST", "RATE_QUANTILES", "describe", "fade", "floor_choice", "floor_steps", "floor_terms",
           "floored", "relative_speeds"]

"""Corrective (DAgger-style) data for CDSP: refit on the states where reproductions leave the demos.

A fitted field f is rolled out from the first sample of every training demonstration and from
the midpoint of every pair of those (:func:`rollout_starts`: starts between the demonstrated
ones, where reproductions from new starts go) by explicit
Euler (:func:`~sosdyn.lfd.rollout.euler_until_rest`; several fields at once: :func:`demo_scores`) with the data's own median time step dt,
stopped when every velocity component of every start has stayed below ``REST_FRACTION`` times the
data's largest velocity component for ``REST_WINDOW`` steps, or after ``ROLLOUT_SPAN`` times the
longest demonstration's duration (and never more than ``sosdyn.limits`` max_rollout_steps). Every
constant is relative to the data, so the rule is the same in any units.

At each rollout state x whose distance to the nearest demonstrated position p (velocity v)
exceeds ``min_dist`` (a length), the corrective label is

    xdot*(x) = v + (p - x) / tau,

the demonstrated velocity plus a pull back onto the demonstration with time constant ``tau``
(in the data's time unit). At most ``MAX_PAIRS`` such pairs per round (evenly thinned) become one
extra pseudo-demonstration that ends at the demonstrations' goal with zero velocity, so the goal
and its check are unchanged (:func:`corrective_demonstration`, :func:`augmented`).

The training score is the mean over the demonstrations of :func:`rollout_deviation`, the
symmetric mean nearest-point distance of the rollout from its first sample, over its own
duration, to it; lower is better. Training data only. CDSP's ``corrective_rounds``
(:class:`~sosdyn.lfd.model.cdsp.CDSP`) runs these functions.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

from sosdyn.errors import SolverError
from sosdyn.limits import check_count, get_limits
from ..data.demonstrations import Demonstration, Demonstrations, sample_step
from ..rollout import euler_blocks_until_rest

ROUNDS, TAU, MIN_DIST = 0, 0.5, 0.02   # CDSP's defaults: refits (off: warp="auto" does better), tau (s), min_dist
REST_FRACTION = 2e-3    # at rest: every |xdot_c| below this fraction of the data's largest |xdot_c|
REST_WINDOW = 4         # ... for this many consecutive steps (the ds-opt protocol's window)
ROLLOUT_SPAN = 5.0      # rollouts last at most this many times the longest demonstration
MAX_PAIRS = 500         # corrective pairs added per round (measured on LASA: 26-shape means in docs)
MIN_PAIRS = 10          # fewer departures than this: the reproductions follow the demos, stop
DIVERGED = 100.0        # a rollout farther than this x the data's extent from the goal has diverged


def nearest(points: np.ndarray, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each row q of ``queries`` (m, n): (index j of the nearest row of ``points`` (T, n),
    distance |q - points_j|), by a k-d tree (memory O(T + m))."""
    dist, j = cKDTree(points).query(queries)
    return j, dist


def corrective_pairs(states, P, V, tau: float, min_dist: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows x of ``states`` farther than ``min_dist`` from every demonstrated position (rows of
    P, velocities V), with labels v_j + (p_j - x) / tau for the nearest p_j. Returns (X, Xdot)."""
    j, dist = nearest(P, states)
    far = dist > min_dist
    X = states[far]
    return X, V[j[far]] + (P[j[far]] - X) / tau


def thin(X: np.ndarray, Xdot: np.ndarray, max_pairs: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``max_pairs`` rows of (X, Xdot), evenly spaced in row order (first and last kept)."""
    if len(X) <= max_pairs:
        return X, Xdot
    keep = np.linspace(0, len(X) - 1, max_pairs).round().astype(int)
    return X[keep], Xdot[keep]


def rollout_deviation(rollout: np.ndarray, demo_pos: np.ndarray) -> float:
    """Symmetric mean nearest-point distance between a rollout (i, n) and a demonstration (T, n):
    (mean_x min_p |x - p| + mean_p min_x |x - p|) / 2."""
    return 0.5 * float(nearest(demo_pos, rollout)[1].mean() + nearest(rollout, demo_pos)[1].mean())


def rest_rule(demos: Demonstrations) -> tuple[float, float, int]:
    """(dt, vel_tol, max_steps) of the training rollouts: the median sample step, REST_FRACTION
    of the largest |velocity component|, ROLLOUT_SPAN x the longest duration / dt (at least
    2 REST_WINDOW steps, at most max_rollout_steps / number of starts)."""
    dt = sample_step(demos)
    vel_tol = REST_FRACTION * max(float(np.abs(d.vel).max()) for d in demos)
    longest = max(float(d.t[-1] - d.t[0]) for d in demos)
    cap = get_limits().max_rollout_steps // len(rollout_starts(demos))
    return dt, vel_tol or np.finfo(float).tiny, int(min(max(np.ceil(ROLLOUT_SPAN * longest / dt),
                                                            2 * REST_WINDOW), cap))


def rollout_starts(demos: Demonstrations) -> np.ndarray:
    """(m + m (m - 1) / 2, n): the m demonstrations' first samples, then (x_i + x_j) / 2 for i < j."""
    first = np.array([d.pos[0] for d in demos])
    i, j = np.triu_indices(len(first), k=1)
    return np.vstack([first, 0.5 * (first[i] + first[j])])


def training_rollouts(field: Callable[[np.ndarray], np.ndarray], demos: Demonstrations) -> list[np.ndarray] | None:
    """Euler rollouts of ``field`` from :func:`rollout_starts` under :func:`rest_rule` (the
    demonstrations' own starts first); None if one diverges: a state or velocity stops being
    finite, or a state gets farther than DIVERGED x the data's extent from the goal (Euler with
    the data's step is unstable for this field)."""
    dt, vel_tol, max_steps = rest_rule(demos)
    return _rollouts(lambda X, live: field(X), demos, rollout_starts(demos), 1, dt, vel_tol, max_steps)[0]


def score_steps(demos: Demonstrations) -> int:
    """The Euler steps of :func:`demo_score`'s rollouts, the longest demonstration's samples + 1 (at
    least 2 REST_WINDOW), checked for all len(demos) starts against max_rollout_steps before any fit
    (ResourceLimitError whose hint names what a CDSP user can change)."""
    steps = max(max(len(d.pos) for d in demos) + 1, 2 * REST_WINDOW)
    check_count(steps * len(demos), "max_rollout_steps",
                f"The rollouts that score warp='auto' ({len(demos)} demonstrations x {steps} steps, one per "
                "sample of the longest)", "fewer samples per demonstration (demos.subsample(k)), or "
                "warp='none' or a warp dict (no scoring rollouts)")
    return steps


def demo_score(field: Callable[[np.ndarray], np.ndarray], demos: Demonstrations) -> float:
    """:func:`training_score` of Euler rollouts of ``field`` from the demonstrations' first samples
    only, as long as the longest demonstration (:func:`rest_rule`'s dt and rest test, :func:`score_steps`):
    the score of the first len(demos) :func:`training_rollouts` at a fraction of their cost."""
    return demo_scores(lambda X, live: field(X), 1, demos)[0]


def demo_scores(field: Callable[[np.ndarray, list], np.ndarray], fields: int, demos: Demonstrations) -> list[float]:
    """:func:`demo_score` of ``fields`` fields at once: ``field(X, live)`` evaluates field b on the
    b-th block of len(demos) rows of X for b in ``live`` (:func:`~sosdyn.lfd.rollout.euler_blocks_until_rest`;
    each block stops by its own rest test), so the per-step work of all of them is shared."""
    dt, vel_tol, _ = rest_rule(demos)
    steps = score_steps(demos)
    starts = np.tile(np.array([d.pos[0] for d in demos]), (fields, 1))
    return [training_score(reps, demos) for reps in _rollouts(field, demos, starts, fields, dt, vel_tol, steps)]


def _rollouts(field, demos, starts, blocks, dt, vel_tol, max_steps) -> list:
    """:func:`~sosdyn.lfd.rollout.euler_blocks_until_rest` from ``starts``: per block its rollouts, or
    None if one diverges (a SolverError, or farther than DIVERGED x the data's extent from the goal)."""
    goal = np.asarray(demos.goal, dtype=float)
    extent = max(float(np.abs(d.pos - goal).max()) for d in demos)
    with np.errstate(over="ignore", invalid="ignore"):     # a diverging rollout is reported as None
        out = euler_blocks_until_rest(field, starts, blocks, dt=dt, max_steps=max_steps, vel_tol=vel_tol,
                                      window=REST_WINDOW)
    return [None if isinstance(reps, SolverError) or max(float(np.abs(x - goal).max()) for x in reps)
            > DIVERGED * extent else reps for reps in out]


def training_score(rollouts: list[np.ndarray] | None, demos: Demonstrations) -> float:
    """Mean :func:`rollout_deviation` of the rollout from each demonstration's first sample (the
    first len(demos) of :func:`training_rollouts`), cut to the demonstration's own length (its
    duration at the data's step), to that demonstration; inf if one diverged. The cut makes a
    rollout that follows the path too slowly score badly: it misses the demonstration's end."""
    if rollouts is None:
        return float("inf")
    return float(np.mean([rollout_deviation(x[:len(d.pos)], d.pos) for x, d in zip(rollouts, demos)]))


def corrective_demonstration(X: np.ndarray, Xdot: np.ndarray, goal: np.ndarray, dt: float,
                             source: str) -> Demonstration:
    """The pairs (X, Xdot) as one pseudo-demonstration sampled every ``dt``, ending at ``goal``
    with zero velocity (so the demonstrations' common goal is unchanged)."""
    pos = np.vstack([X, goal])
    vel = np.vstack([Xdot, np.zeros_like(goal)[None, :]])
    return Demonstration(dt * np.arange(len(pos)), pos, vel, source)


def augmented(demos: Demonstrations, extra: list[Demonstration]) -> Demonstrations:
    """The demonstrations followed by the pseudo-demonstrations ``extra`` (same name, units and columns)."""
    return Demonstrations(list(demos) + list(extra), demos.name, demos.units, columns=demos.columns)


__all__ = ["DIVERGED", "MAX_PAIRS", "MIN_DIST", "MIN_PAIRS", "REST_FRACTION", "REST_WINDOW",
           "ROLLOUT_SPAN", "ROUNDS", "TAU", "augmented", "corrective_demonstration",
           "corrective_pairs", "demo_score", "demo_scores", "nearest", "rest_rule", "rollout_deviation",
           "rollout_starts", "score_steps", "thin", "training_rollouts", "training_score"]

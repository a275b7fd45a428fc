"""Corrective (DAgger-style) data for CDSP: refit on the states where reproductions leave the demos.

A fitted field f is rolled out (explicit Euler, step ``dt``, stopped at rest as in
:func:`~sosdyn.lfd.rollout.euler_until_rest`) from every training demonstration's sample
``start_index``. At each rollout state x whose distance to the nearest training sample p
(velocity v) exceeds ``min_dist`` (a fraction of the data's scale), the corrective label is

    xdot*(x) = v + (p - x) / tau,

the demonstrated velocity plus a pull back onto the demonstration with time constant ``tau``
(seconds). Those pairs (at most ``max_extra`` per round, evenly thinned) are added to the
training data as one extra pseudo-demonstration ending at the demonstrations' goal with zero
velocity (so the goal and its check are unchanged), and CDSP is refitted on the aggregate;
``rounds`` times. Every round's model is an ordinary certified CDSP (the corrective pairs
only change the least-squares data term), so the contraction guarantee is unchanged.

The returned model is the round (0 = the plain fit) with the lowest training score: by default
the symmetric mean nearest-point distance :func:`rollout_deviation` of the rollouts to their
demonstrations, or ``score(model, demos)`` (e.g. the protocol's training DTWD, supplied by the
evaluation layer). Training data only.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError, NotFittedError
from .cdsp import CDSP
from .data import Demonstration, Demonstrations, check_demonstrations
from .rollout import euler_until_rest


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


def rollout_deviation(rollout: np.ndarray, demo_pos: np.ndarray) -> float:
    """Symmetric mean nearest-point distance between a rollout (i, n) and a demonstration (T, n):
    (mean_x min_p |x - p| + mean_p min_x |x - p|) / 2."""
    return 0.5 * float(nearest(demo_pos, rollout)[1].mean() + nearest(rollout, demo_pos)[1].mean())


class CorrectiveCDSP:
    """CDSP refitted on corrective data from its own training rollouts (module docstring).

    Parameters: ``cdsp_params`` (dict of :class:`CDSP` keyword arguments), ``rounds`` (refits,
    >= 0), ``tau`` (s, > 0), ``min_dist`` (fraction of the data scale, >= 0), ``max_extra``
    (corrective pairs added per round), ``score`` (None or a callable (model, demos) -> float,
    lower is better), ``start_index`` (rollouts start at this sample of each
    training demonstration), ``dt``, ``max_steps``, ``vel_tol``, ``window`` (the Euler rollout
    and its rest rule). Learned: ``model_`` (the chosen CDSP), ``round_`` (its round),
    ``scores_`` (training score of every round), ``n_extra_`` (pairs added per round).
    """

    name = "CDSP corrective"

    def __init__(self, cdsp_params=None, rounds=2, tau=0.5, min_dist=0.02, max_extra=500, score=None, start_index=0,
                 dt=0.01, max_steps=3000, vel_tol=0.1, window=4):
        self.cdsp_params = dict(cdsp_params or {})
        self.rounds, self.tau, self.min_dist, self.max_extra, self.score = rounds, tau, min_dist, max_extra, score
        self.start_index, self.dt, self.max_steps, self.vel_tol, self.window = (start_index, dt, max_steps,
                                                                                 vel_tol, window)

    def _check(self):
        for name, value, lo in (("rounds", self.rounds, 0), ("max_extra", self.max_extra, 10),
                                ("start_index", self.start_index, 0)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
                raise InputError(f"{name} must be an integer >= {lo}, got {value!r}. Try: the default.")
        for name, value in (("tau", self.tau), ("min_dist", self.min_dist)):
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not value >= 0 \
                    or not np.isfinite(value) or (name == "tau" and value == 0):
                raise InputError(f"{name} must be a finite number {'> 0' if name == 'tau' else '>= 0'}, "
                                 f"got {value!r}. Try: tau=0.5, min_dist=0.02.")

    def _rollouts(self, model: CDSP, demos: Demonstrations) -> list[np.ndarray]:
        short = [i for i, d in enumerate(demos) if len(d.pos) <= self.start_index]
        if short:
            raise InputError(f"demo {short[0]} has {len(demos[short[0]].pos)} samples, not more than "
                             f"start_index = {self.start_index}. Try: a smaller start_index.")
        starts = np.array([d.pos[self.start_index] for d in demos])
        return euler_until_rest(model.predict, starts, dt=self.dt, max_steps=self.max_steps,
                                vel_tol=self.vel_tol, window=self.window)

    def fit(self, demos):
        """Fit round 0, then ``rounds`` refits on the demos plus the aggregated corrective data;
        keep the round with the lowest training score. Returns self."""
        self._check()
        demos = check_demonstrations(demos)
        P, V = demos.stacked()
        goal = np.asarray(demos.goal, dtype=float)
        step = float(np.median(np.concatenate([np.diff(d.t) for d in demos])))
        models, self.scores_, self.n_extra_, extra = [], [], [], []
        for r in range(self.rounds + 1):
            train = Demonstrations(list(demos) + extra, demos.name, demos.units)
            models.append(CDSP(**self.cdsp_params).fit(train))
            reps = self._rollouts(models[-1], demos) if self.score is None or r < self.rounds else None
            self.scores_.append(float(np.mean([rollout_deviation(x, d.pos) for x, d in zip(reps, demos)]))
                                if self.score is None else float(self.score(models[-1], demos)))
            if r == self.rounds:
                break
            X, Xdot = corrective_pairs(np.vstack(reps), P, V, self.tau, self.min_dist * models[0].scale_)
            if len(X) > self.max_extra:
                keep = np.linspace(0, len(X) - 1, self.max_extra).round().astype(int)
                X, Xdot = X[keep], Xdot[keep]
            self.n_extra_.append(len(X))
            if len(X) < 9:                 # reproductions already on the demos: nothing to correct
                break
            pos, vel = np.vstack([X, goal]), np.vstack([Xdot, np.zeros_like(goal)])
            extra.append(Demonstration(step * np.arange(len(pos)), pos, vel, f"corrective round {r + 1}"))
        self.round_ = int(np.argmin(self.scores_))
        self.model_ = models[self.round_]
        self.certified_ = self.model_.certified_
        return self

    def predict(self, X):
        """Velocities of the chosen round's CDSP at the states X (m, n)."""
        if not hasattr(self, "model_"):
            raise NotFittedError("this CorrectiveCDSP is not fitted yet; call fit(demos) first")
        return self.model_.predict(X)


__all__ = ["CorrectiveCDSP", "corrective_pairs", "nearest", "rollout_deviation"]

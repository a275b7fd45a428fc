"""The one-state evaluator of a second-order model: ``step(x, v, goal=None) -> acceleration``.

a = (s / T^2) sum_k h_k(e) C_k e with e = ((x - g)/s, v T/s) (:func:`~sosdyn.lfd.fit.second_order.acceleration_at`,
the one formula; this class checks one state and keeps the model's numbers). The certificate does
not involve h, g, s or T, so a moved goal keeps it: the state still converges to (goal, 0).
"""
from __future__ import annotations

import numpy as np

from ..fit.gmm import PositionMixture
from ..fit.second_order import acceleration_at
from .states import as_state


class SecondOrderPredictor:
    """``pred(x, v, goal=None)`` (also ``pred.step``): the acceleration (n,) at one state (x, v)."""

    def __init__(self, goal: np.ndarray, length: float, time: float, mixture: PositionMixture, C: np.ndarray):
        self.goal, self.length, self.time = np.array(goal, dtype=float), float(length), float(time)
        self.mixture, self.C, self.dim = mixture, np.array(C, dtype=float), len(goal)

    def __call__(self, x, v, goal=None) -> np.ndarray:
        n = self.dim
        g = self.goal if goal is None else as_state(goal, n, "goal")
        X, V = as_state(x, n, "x")[None], as_state(v, n, "v")[None]
        return acceleration_at(X, V, g, self.length, self.time, self.mixture, self.C)[0]

    step = __call__

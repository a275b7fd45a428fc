"""A linear model with known answers and demonstrations it reproduces exactly; a DTW oracle."""

import numpy as np
import pytest

from sosdyn.evaluation.metrics import DTWDistance, warping_path_length
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.rollout import rollout

GOAL = np.array([1.0, -2.0])


class LinearModel:
    """xdot = -rate (x - goal): x(t) = goal + (x0 - goal) exp(-rate t)."""

    name = "linear"

    def __init__(self, goal=GOAL, rate=1.0):
        self.goal, self.rate = np.asarray(goal, float), rate

    def field(self, X, goal):
        return -self.rate * (X - goal)

    def predict(self, X):
        return self.field(X, self.goal)

    def rollout(self, x0, duration, dt=0.01, goal=None, perturbations=(), goal_changes=()):
        return rollout(self.field, x0, duration=duration, dt=dt, goal=self.goal if goal is None else goal,
                       perturbations=perturbations, goal_changes=goal_changes)


def exponential_demo(x0, goal=GOAL, duration=6.0, T=301):
    t = np.linspace(0.0, duration, T)
    pos = goal + (np.asarray(x0, float) - goal) * np.exp(-t)[:, None]
    return Demonstration(t, pos, -(pos - goal))


@pytest.fixture
def exp_model():
    return LinearModel()


@pytest.fixture
def exp_demos():
    """Three demos of the linear model (units mm), scale about 10 mm."""
    starts = ([9.0, 3.0], [6.0, -9.0], [-5.0, 4.0])
    return Demonstrations([exponential_demo(x0) for x0 in starts], "exp", "mm")


@pytest.fixture
def exp_goal():
    return GOAL.copy()


@pytest.fixture
def exp_model_cls():
    """The LinearModel class (construct with another goal or rate)."""
    return LinearModel


@pytest.fixture
def make_exp_demo():
    """exponential_demo(x0, goal=GOAL, duration=6.0, T=301)."""
    return exponential_demo


def double_loop_dtw(a, b) -> DTWDistance:
    """The textbook O(N M) recurrence, one cell at a time: ``D[i, j] = ||a_i - b_j|| +
    min(D[i-1, j-1], D[i-1, j], D[i, j-1])``, D[0, 0] = 0 and inf on the rest of row and
    column 0; the path length is traced back through D."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    N, M = len(a), len(b)
    D = np.full((N + 1, M + 1), np.inf)
    D[0, 0] = 0.0
    for i in range(1, N + 1):
        for j in range(1, M + 1):
            cost = float(np.linalg.norm(a[i - 1] - b[j - 1]))
            D[i, j] = cost + min(D[i - 1, j - 1], D[i - 1, j], D[i, j - 1])
    length = warping_path_length(D)
    return DTWDistance(float(D[N, M]), float(D[N, M]) / length, (N, M), length)


@pytest.fixture
def reference_dtw():
    """The double-loop DTW (known-correct, slow) to check :func:`sosdyn.evaluation.metrics.dtwd`."""
    return double_loop_dtw

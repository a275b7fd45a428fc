"""sosdyn.evaluation.realdata: reproductions read at the demos' period (curves sampled alike), the rest cut
of a time-indexed model's rollout."""
from __future__ import annotations

import numpy as np
import pytest

from sosdyn.evaluation import realdata
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.data.demonstrations import Demonstration

PERIOD, SPAN = 0.02, 2.0


def demo_curve(t):
    return np.column_stack([np.cos(t), np.sin(2 * t)])


def rollout_curve(t):
    """Another curve than the demo's (so its DTWD is not 0), smooth: |x''| <= 1 + 0.3 * 1.5^2 + 4."""
    return np.column_stack([np.cos(t) + 0.3 * np.sin(1.5 * t), np.sin(2 * t) + 0.1 * t])


@pytest.mark.parametrize("dt", [0.0025, 0.005, 0.007, 0.01, 0.013, 0.02])
def test_a_denser_or_sparser_rollout_of_the_same_curve_scores_the_same(dt):
    """The rollout of one curve sampled every dt, read at the demo's period, scores the DTWD of the curve's
    own samples at the demo's instants, up to the interpolation: linear interpolation between samples dt
    apart is off by at most dt^2/8 max|x''| per point, and the cumulative DTW (a minimum over warping paths
    of sums of at most N + M - 1 point distances, each 1-Lipschitz in the points) moves by at most
    (N + M - 1) times that. Read as integrated instead, the dense rollouts count every extra point."""
    t_demo = np.arange(0.0, SPAN + 1e-9, PERIOD)
    demo = Demonstration.from_positions(t_demo, demo_curve(t_demo))
    t = np.arange(0.0, SPAN + dt, dt)[: int(np.ceil(SPAN / dt - 1e-9)) + 1]         # covers [0, SPAN], ends < SPAN + dt
    path = rollout_curve(t)
    read = realdata.at_period(path, demo, dt)
    assert read.shape == demo.pos.shape
    exact = dtwd(rollout_curve(t_demo), demo.pos).total
    n = len(t_demo)
    tol = (2 * n - 1) * dt ** 2 / 8 * (1 + 0.3 * 1.5 ** 2 + 4)
    assert abs(dtwd(read, demo.pos).total - exact) <= tol
    if dt * 4 <= PERIOD:                                 # 4x the points: the raw sum counts them
        assert dtwd(path, demo.pos).total > 2 * exact


def test_read_at_the_period_of_the_demo_itself_is_its_samples():
    t = np.arange(0, 2.0001, 0.01)
    path = demo_curve(t)
    demo = Demonstration.from_positions(t[::2], path[::2])
    read = realdata.at_period(path, demo)
    assert read.shape == demo.pos.shape and np.abs(read - demo.pos).max() < 1e-12
    assert dtwd(read, demo.pos).total < 1e-9 < dtwd(path, demo.pos).total


def test_rest_cut_stops_where_the_euler_rule_would():
    """A path moving at 1 unit/s for 1 s, then still: the rows up to the last of the first `window` calm steps (the
    last moving row, 100, and window - 1 still ones), as euler_until_rest keeps x_0..x_{i-1}."""
    dt, window = 0.01, 4
    moving = np.arange(101)[:, None] * dt * np.ones((1, 2))
    path = np.vstack([moving, np.repeat(moving[-1:], 50, axis=0)])
    cut = realdata.rest_cut(path, vel_tol=0.1, dt=dt, window=window)
    assert len(cut) == 100 + window and np.array_equal(cut, path[:len(cut)])
    assert realdata.rest_cut(moving, vel_tol=0.1, dt=dt, window=window) is moving      # never at rest
    assert realdata.rest_cut(path[:3], vel_tol=0.1, dt=dt, window=window).shape == (3, 2)

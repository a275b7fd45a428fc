"""DMP baseline on LASA Leaf_1: reproduction, moved goal, pushes, typed errors."""

import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.evaluation.baselines import DMP


def _shape_size(demos):
    return np.ptp(np.vstack([d.pos for d in demos]), axis=0).max()


@pytest.fixture(scope="module")
def leaf_dmp(leaf_1):
    return DMP(n_weights_per_dim=25).fit(leaf_1)


def test_dmp_reproduces_each_demonstration(leaf_1, leaf_dmp):
    for i, demo in enumerate(leaf_1):
        trajectory = leaf_dmp.rollout(demo.pos[0], demo.duration, demo=i)
        replay = np.column_stack([np.interp(demo.t - demo.t[0], trajectory.t, trajectory.pos[:, j])
                                  for j in range(leaf_1.dim)])
        error = np.linalg.norm(replay - demo.pos, axis=1).mean()
        assert error < 0.02 * _shape_size(leaf_1), (i, error)     # measured ≤ 0.45 mm of 50 mm


def test_dmp_reaches_a_moved_goal_and_logs_events(leaf_1, leaf_dmp):
    demo, size = leaf_1[0], _shape_size(leaf_1)
    new_goal = leaf_dmp.goal_ + np.array([10.0, -5.0])
    push = np.array([3.0, 3.0])
    trajectory = leaf_dmp.rollout(demo.pos[0], 4 * demo.duration, perturbations=[(1.0, push)],
                                  goal_changes=[(0.5 * demo.duration, new_goal)])
    assert np.linalg.norm(trajectory.pos[-1] - new_goal) < 0.005 * size
    assert [e["kind"] for e in trajectory.events] == ["push", "goal_change"]
    np.testing.assert_allclose(trajectory.events[0]["after"] - trajectory.events[0]["before"], push)
    k = np.searchsorted(trajectory.t, 1.0)
    np.testing.assert_allclose(trajectory.pos[k], trajectory.events[0]["after"])
    np.testing.assert_allclose(trajectory.goal_history[-1], new_goal)


def test_dmp_is_time_indexed_and_checks_inputs(leaf_1, leaf_dmp):
    with pytest.raises(NotImplementedError, match="time-indexed"):
        leaf_dmp.predict(np.zeros((1, 2)))
    with pytest.raises(InputError, match="demo 7"):
        leaf_dmp.rollout(leaf_1[0].pos[0], 1.0, demo=7)
    with pytest.raises(InputError, match="push"):
        leaf_dmp.rollout(leaf_1[0].pos[0], 1.0, perturbations=[(2.0, [1.0, 0.0])])
    with pytest.raises(InputError, match="larger than duration"):
        leaf_dmp.rollout(leaf_1[0].pos[0], 1e-4)
    with pytest.raises(InputError, match="n_weights_per_dim"):
        DMP(n_weights_per_dim=1).fit(leaf_1)

"""The robustness protocol: seeded events, the shifted reference, and scores."""

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.perturbations import (
    GoalChange,
    Push,
    Scenario,
    make_events,
    robustness,
    shifted_reference,
)
from sosdyn.lfd.data.demonstrations import Demonstrations
from sosdyn.lfd.rollout import Trajectory


def diagonal(demos):
    X, _ = demos.stacked()
    return np.linalg.norm(X.max(axis=0) - X.min(axis=0))


def test_push_events_are_seeded_and_scaled(exp_demos):
    events = make_events(exp_demos, "push", n=2, seed=3, amplitude_frac=0.1, at_frac=0.25)
    assert len(events) == 6 and [e.demo_index for e in events] == [0, 0, 1, 1, 2, 2]
    for scenario in events:
        (push,) = scenario.pushes
        assert scenario.goal_changes == () and isinstance(push, Push)
        assert push.time == pytest.approx(1.5)  # 0.25 of the 6 s demos
        assert np.linalg.norm(push.dx) == pytest.approx(0.1 * diagonal(exp_demos))
    again = make_events(exp_demos, "push", n=2, seed=3, amplitude_frac=0.1, at_frac=0.25)
    other = make_events(exp_demos, "push", n=2, seed=4, amplitude_frac=0.1, at_frac=0.25)
    assert all(np.array_equal(a.pushes[0].dx, b.pushes[0].dx) for a, b in zip(events, again))
    assert not np.allclose(events[0].pushes[0].dx, other[0].pushes[0].dx)
    assert not np.allclose(events[0].pushes[0].dx, events[1].pushes[0].dx)


def test_goal_change_events(exp_demos):
    events = make_events(exp_demos, "goal_change", seed=0, amplitude_frac=0.2, at_frac=0.5)
    assert len(events) == 3
    for scenario in events:
        (change,) = scenario.goal_changes
        assert scenario.pushes == () and isinstance(change, GoalChange) and change.time == pytest.approx(3.0)
        assert np.linalg.norm(change.new_goal - exp_demos.goal) == pytest.approx(0.2 * diagonal(exp_demos))


@pytest.mark.parametrize(
    "kwargs, message",
    [({"kind": "shove"}, "kind must be"), ({"n": 0}, "n must be"), ({"at_frac": 1.5}, "at_frac"),
     ({"amplitude_frac": -1.0}, "amplitude_frac")],
)
def test_make_events_bad_inputs(exp_demos, kwargs, message):
    with pytest.raises(InputError, match=message):
        make_events(exp_demos, **({"kind": "push"} | kwargs))


def test_shifted_reference_translates_the_part_after_each_change(exp_demos):
    demo, goal = exp_demos[0], exp_demos.goal
    first, second = goal + [1.0, 0.0], goal + [0.0, -3.0]
    ref = shifted_reference(demo, [GoalChange(4.0, second), GoalChange(2.0, first)], goal)
    tau = demo.t - demo.t[0]
    np.testing.assert_array_equal(ref[tau < 2.0], demo.pos[tau < 2.0])
    middle = (tau >= 2.0) & (tau < 4.0)
    np.testing.assert_allclose(ref[middle], demo.pos[middle] + [1.0, 0.0])
    np.testing.assert_allclose(ref[tau >= 4.0], demo.pos[tau >= 4.0] + [0.0, -3.0])
    np.testing.assert_array_equal(shifted_reference(demo, (), goal), demo.pos)


class ReferenceFollower:
    """A 'model' whose rollout is exactly the shifted reference of its single demo."""

    def __init__(self, demos):
        self.demos = demos

    def rollout(self, x0, duration, dt, perturbations=(), goal_changes=()):
        demo = self.demos[0]
        pos = shifted_reference(demo, goal_changes, self.demos.goal)
        goals = np.tile(self.demos.goal, (len(pos), 1))
        for time, new_goal in goal_changes:
            goals[demo.t - demo.t[0] >= time] = new_goal
        return Trajectory(demo.t - demo.t[0], pos, goals)


def test_a_model_following_the_shifted_demo_scores_zero(exp_demos):
    demos = exp_demos[:1]
    events = make_events(demos, "goal_change", n=3, seed=1)
    result = robustness(ReferenceFollower(demos), demos, events, duration_factor=1.0)
    assert result["dtwd"] == [0.0, 0.0, 0.0] and result["fraction_converged"] == 1.0


def test_linear_model_recovers_from_pushes(exp_model, exp_demos):
    events = make_events(exp_demos, "push", n=2, seed=0, amplitude_frac=0.2)
    result = robustness(exp_model, exp_demos, events)
    assert result["converged"] == [True] * 6 and result["failures"] == []
    assert max(result["goal_error"]) < 0.01 and min(result["dtwd_per_point"]) > 0.01
    traj = result["trajectories"][0]
    assert traj.t[-1] == pytest.approx(9.0) and traj.events[0]["kind"] == "push"  # 1.5 x 6 s
    unpushed = robustness(exp_model, exp_demos, make_events(exp_demos, "push", amplitude_frac=0.0),
                          duration_factor=1.0)
    assert max(unpushed["dtwd_per_point"]) < 1e-5


def test_linear_model_follows_a_goal_change(exp_model, exp_demos):
    events = make_events(exp_demos, "goal_change", seed=2, amplitude_frac=0.2, at_frac=0.3)
    result = robustness(exp_model, exp_demos, events)
    assert result["fraction_converged"] == 1.0
    for scenario, traj, error in zip(events, result["trajectories"], result["goal_error"]):
        np.testing.assert_array_equal(traj.goal_history[-1], scenario.goal_changes[0].new_goal)
        assert error < 0.05
    assert set(result["mean"]) == {"dtwd", "dtwd_per_point", "goal_error"}


def test_solver_failures_are_recorded(exp_demos):
    class Diverging:
        def rollout(self, *args, **kwargs):
            raise SolverError("blew up")

    result = robustness(Diverging(), exp_demos, make_events(exp_demos, "push"))
    assert result["fraction_converged"] == 0.0 and result["dtwd"] == [np.inf] * 3
    assert result["mean"]["dtwd"] == np.inf and result["std"]["dtwd"] == np.inf
    assert len(result["failures"]) == 3 and "blew up" in result["failures"][0]["reason"]


def test_robustness_bad_inputs(exp_model, exp_demos):
    with pytest.raises(InputError, match="Scenario"):
        robustness(exp_model, exp_demos, [(1.0, [0.0, 0.0])])
    with pytest.raises(InputError, match="Scenario"):
        robustness(exp_model, exp_demos, [Scenario(5)])
    with pytest.raises(InputError, match="empty"):
        robustness(exp_model, exp_demos, [])
    with pytest.raises(InputError, match="duration_factor"):
        robustness(exp_model, exp_demos, make_events(exp_demos, "push"), duration_factor=0)
    with pytest.raises(InputError, match="non-empty"):
        robustness(exp_model, Demonstrations([]), [])


def test_slow_model_is_rolled_out_until_it_reaches_the_goal(exp_model_cls, exp_demos):
    """Rate 0.2/s from ~10 mm: after 1.5 x 6 s it is still ~1.7 mm away (not converged); with
    max_duration_factor the run is doubled to 18 s, where it is ~0.3 mm away (converged)."""
    slow = exp_model_cls(rate=0.2)
    events = make_events(exp_demos, "push", amplitude_frac=0.0)
    cut = robustness(slow, exp_demos, events)
    assert cut["fraction_converged"] == 0.0 and min(cut["goal_error"]) > 1.0
    long = robustness(slow, exp_demos, events, max_duration_factor=20)
    assert long["fraction_converged"] == 1.0 and max(long["goal_error"]) < 0.5
    assert [t.t[-1] for t in long["trajectories"]] == pytest.approx([18.0] * 3)
    never = robustness(exp_model_cls(rate=0.01), exp_demos, events, max_duration_factor=4)
    assert never["fraction_converged"] == 0.0
    assert [t.t[-1] for t in never["trajectories"]] == pytest.approx([24.0] * 3)   # capped at 4 x 6 s
    with pytest.raises(InputError, match="max_duration_factor"):
        robustness(slow, exp_demos, events, max_duration_factor=1.0)

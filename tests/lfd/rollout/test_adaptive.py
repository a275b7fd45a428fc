"""Adaptive integration: rollouts (analytic solutions, pushes, goal changes, sizes, typed errors)
and batched final states."""

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InputError, ResourceLimitError, SolverError
from sosdyn.lfd.rollout import Trajectory, check_rollout_size, final_states, rollout

GOAL = np.array([1.0, -2.0])
X0 = np.array([4.0, 3.0])


def linear(X, goal):
    """xdot = -(x - goal): x(t) = goal + (x0 - goal) exp(-t)."""
    return -(X - goal)


def analytic(x0, goal, t):
    return goal + (np.asarray(x0) - goal) * np.exp(-np.asarray(t))[:, None]


def test_linear_field_matches_the_analytic_solution():
    traj = rollout(linear, X0, duration=3.0, dt=0.01, goal=GOAL)
    assert isinstance(traj, Trajectory) and traj.events == []
    assert traj.t.shape == (301,) and traj.t[0] == 0 and traj.t[-1] == 3.0
    np.testing.assert_allclose(np.diff(traj.t), 0.01, rtol=1e-9)
    np.testing.assert_allclose(traj.pos, analytic(X0, GOAL, traj.t), atol=1e-5)
    np.testing.assert_array_equal(traj.goal_history, np.tile(GOAL, (301, 1)))


def test_grid_ends_exactly_at_duration():
    traj = rollout(linear, X0, duration=1.0, dt=0.3, goal=GOAL)
    np.testing.assert_allclose(traj.t, [0, 1 / 3, 2 / 3, 1])


def test_push_lands_where_expected():
    dx = np.array([-2.0, 1.0])
    traj = rollout(linear, X0, duration=3.0, dt=0.01, goal=GOAL, perturbations=[(1.0, dx)])
    k = 100
    before = analytic(X0, GOAL, [1.0])[0]
    np.testing.assert_allclose(traj.pos[k - 1], analytic(X0, GOAL, [0.99])[0], atol=1e-5)
    np.testing.assert_allclose(traj.pos[k], before + dx, atol=1e-5)  # right-continuous
    np.testing.assert_allclose(traj.pos[k:], analytic(before + dx, GOAL, traj.t[k:] - 1.0), atol=1e-5)
    (event,) = traj.events
    assert event["kind"] == "push" and event["time"] == 1.0
    np.testing.assert_allclose(event["after"] - event["before"], dx)


def test_goal_change_between_grid_points():
    new_goal = np.array([-3.0, 0.5])
    tc = 1.234
    traj = rollout(linear, X0, duration=4.0, dt=0.01, goal=GOAL, goal_changes=[(tc, new_goal)])
    after = traj.t >= tc
    np.testing.assert_array_equal(traj.goal_history[~after], np.tile(GOAL, ((~after).sum(), 1)))
    np.testing.assert_array_equal(traj.goal_history[after], np.tile(new_goal, (after.sum(), 1)))
    x_change = analytic(X0, GOAL, [tc])[0]
    np.testing.assert_allclose(traj.pos[after], analytic(x_change, new_goal, traj.t[after] - tc), atol=1e-5)
    assert traj.events[0]["kind"] == "goal_change"
    np.testing.assert_array_equal(traj.events[0]["before"], GOAL)


def test_events_at_the_ends_and_together():
    dx = np.array([0.5, 0.5])
    traj = rollout(linear, X0, duration=1.0, dt=0.1, goal=GOAL,
                   perturbations=[(0.0, dx), (1.0, dx), (0.5, dx), (0.5, dx)], goal_changes=[(0.5, X0)])
    np.testing.assert_allclose(traj.pos[0], X0 + dx)
    np.testing.assert_allclose(traj.pos[5], analytic(X0 + dx, GOAL, [0.5])[0] + 2 * dx, atol=1e-5)
    mid = traj.pos[5]
    np.testing.assert_allclose(traj.pos[-1], analytic(mid, X0, [0.5])[0] + dx, atol=1e-5)
    assert [e["kind"] for e in traj.events] == ["push", "goal_change", "push", "push", "push"]


def test_stiff_linear_field():
    traj = rollout(lambda X, g: -1e4 * (X - g), X0, duration=1.0, dt=0.01, goal=GOAL)
    np.testing.assert_allclose(traj.pos[-1], GOAL, atol=1e-6)


def test_one_dimensional_and_stable_cubic_field():
    traj = rollout(lambda X, g: -((X - g) ** 3), [3.0], duration=2.0, dt=0.05, goal=[1.0])
    t = traj.t
    np.testing.assert_allclose(traj.pos[:, 0], 1 + 2 / np.sqrt(1 + 8 * t), atol=1e-5)  # e' = -e^3


def test_blow_up_raises_solver_error():
    with pytest.raises(SolverError) as info:
        rollout(lambda X, g: X**3, X0, duration=2.0, dt=0.01, goal=GOAL)
    assert info.value.status == "solver_error" and "smaller dt" in str(info.value)


def test_field_returning_nan_raises_solver_error():
    with pytest.raises(SolverError, match="NaN"):
        rollout(lambda X, g: np.full_like(X, np.nan), X0, duration=1.0, dt=0.1, goal=GOAL)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"x0": [np.nan, 0.0]}, "x0 contains NaN"),
        ({"x0": np.zeros((2, 1))}, "x0 has shape"),
        ({"goal": [0.0, 0.0, 0.0]}, "goal has shape"),
        ({"duration": 0.0}, "duration must be"),
        ({"duration": np.inf}, "duration must be"),
        ({"dt": -0.1}, "dt must be"),
        ({"dt": 5.0}, "larger than duration"),
        ({"perturbations": [(1.5, [1.0, 0.0])]}, "not inside"),
        ({"perturbations": [(-0.1, [1.0, 0.0])]}, "not inside"),
        ({"perturbations": [(0.5, [1.0])]}, "push 0 vector has shape"),
        ({"perturbations": [0.5]}, "must be a pair"),
        ({"goal_changes": [(0.5, [np.inf, 0.0])]}, "goal_change 0 vector contains NaN"),
        ({"integrator": "Euler"}, "integrator must be"),
        ({"field": "not callable"}, "field must be callable"),
        ({"field": lambda X, g: X[:, :1]}, "returned shape"),
    ],
)
def test_bad_inputs_raise_input_error(kwargs, message):
    args = {"field": linear, "x0": X0, "duration": 1.0, "dt": 0.1, "goal": GOAL} | kwargs
    field, x0 = args.pop("field"), args.pop("x0")
    with pytest.raises(InputError, match=message):
        rollout(field, x0, **args)


# ---------------------------------------------------------------- rollout sizes and inputs

def test_rollout_size_is_checked_before_allocating():
    assert check_rollout_size(3.0, 0.01, 2) == 301
    with pytest.raises(ResourceLimitError, match=r"sample count is 1e\+11, over the limit max_rollout_steps="
                                                 r"10000000.*larger dt or a shorter duration"):
        rollout(linear, [0.0, 0.0], duration=1e9, dt=0.01, goal=GOAL)
    with pytest.raises(ResourceLimitError, match="max_rollout_steps"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=1e-9, goal=GOAL)
    with pytest.raises(ResourceLimitError, match="inf"):
        rollout(linear, [0.0, 0.0], duration=1e300, dt=1e-300, goal=GOAL)
    with sd.limits(max_rollout_steps=10**12), \
            pytest.raises(ResourceLimitError, match=r"arrays needs about 5960\.5 GiB.*max_bytes"):
        rollout(linear, [0.0, 0.0], duration=1e9, dt=0.01, goal=GOAL)


def test_rollout_step_limit_boundary():
    with sd.limits(max_rollout_steps=51):
        assert rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL).t.shape == (51,)
    with sd.limits(max_rollout_steps=50), pytest.raises(ResourceLimitError, match="is 51, over the limit"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL)
    with sd.limits(max_bytes=51 * 8 * 8 - 1), pytest.raises(ResourceLimitError, match="max_bytes"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL)   # 51 x (3*2 + 2) x 8 bytes
    with sd.limits(max_bytes=51 * 8 * 8):
        assert rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL).pos.shape == (51, 2)


@pytest.mark.parametrize("kwargs, message", [
    ({"dt": 0}, "dt must be a finite number > 0"),
    ({"dt": None}, "dt must be"),
    ({"dt": np.nan}, "dt must be"),
    ({"dt": True}, "dt must be"),
    ({"duration": True}, "duration must be"),
    ({"duration": np.nan}, "duration must be"),
    ({"x0": [np.inf, 0.0]}, "x0 contains NaN or inf"),
    ({"goal": [1.0]}, r"goal has shape \(1,\)"),
    ({"perturbations": None}, "push events must be a list of pairs"),
    ({"goal_changes": {0.5: [0, 0]}}, "goal_change events must be a list of pairs"),
    ({"perturbations": [(np.nan, [1.0, 0.0])]}, "not inside"),
    ({"perturbations": [(0.5, [1.0, np.nan])]}, "push 0 vector contains NaN"),
])
def test_rollout_inputs(kwargs, message):
    args = {"x0": [0.0, 0.0], "duration": 1.0, "dt": 0.1, "goal": GOAL} | kwargs
    with pytest.raises(InputError, match=message):
        rollout(linear, args.pop("x0"), **args)


def test_numpy_scalars_accepted_by_rollout():
    traj = rollout(linear, [0.0, 0.0], duration=np.float32(1.0), dt=np.float64(0.1), goal=GOAL)
    assert traj.t.shape == (11,)
    np.testing.assert_allclose(traj.pos[-1], GOAL * (1 - np.exp(-1.0)), atol=1e-5)


def test_blow_ups_raise_a_typed_error_never_nan():
    with pytest.raises(SolverError, match=r"at t = 0\.99.*blew up") as info:     # xdot = x^2: x = 1/(1-t)
        rollout(lambda X, g: X ** 2, [1.0], duration=2.0, dt=0.1, goal=[0.0])
    assert info.value.status == "solver_error"
    with pytest.raises(SolverError, match="not finite at t = 0"):  # a push to inf
        rollout(linear, [1e308, 0.0], duration=1.0, dt=0.1, goal=GOAL, perturbations=[(0.0, [1e308, 0])])


# ---------------------------------------------------------------- batched final states


def test_batched_final_states_match_the_exact_solution():
    starts = np.array([[9.0, 3.0], [-5.0, 4.0], [100.0, -50.0]])
    final, reasons = final_states(lambda X, g: -(X - g), starts, 3.0, GOAL)
    np.testing.assert_allclose(final, GOAL + (starts - GOAL) * np.exp(-3.0), rtol=1e-5)
    assert reasons == [None, None, None]
    for integrator in ("BDF", "Radau"):
        other, _ = final_states(lambda X, g: -(X - g), starts, 3.0, GOAL, integrator=integrator)
        np.testing.assert_allclose(other, final, rtol=1e-4)


    with pytest.raises(InputError, match="integrator must be one of"):
        final_states(linear, np.zeros((1, 2)), 1.0, GOAL, integrator="RK45")

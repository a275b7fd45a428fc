"""Bounded, unit-independent rollouts (issue 23, items 3 and 4): a call and time budget with a
typed error saying how far the rollout got, and an absolute tolerance relative to the motion."""
import time

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InputError, SolverError, WorkLimitError
from sosdyn.lfd.rollout import ATOL_REL, motion_scale, parse_events, rollout
from sosdyn.lfd.rollout.events import WorkMeter

GOAL = np.array([1.0, -2.0])


def cubic(X, goal):
    """xdot = -(x - goal)^3 componentwise: stiff far away (|x - g| ~ 1e4 gives rates ~ 1e8)."""
    return -(X - goal) ** 3


def test_a_rollout_over_its_call_budget_says_how_far_it_got():
    x0 = GOAL + 1e4
    with sd.limits(max_rollout_calls=300):
        with pytest.raises(WorkLimitError, match=r"stopped after 301 field calls .* at t = .* of 10 s, x = .*"
                                                 r"from the goal\): over max_rollout_calls = 300") as info:
            rollout(cubic, x0, duration=10.0, dt=0.01, goal=GOAL, integrator="RK45")
    exc = info.value
    assert isinstance(exc, SolverError) and exc.status == "solver_error"
    assert exc.calls == 301 and 0 < exc.t < 10.0 and np.all(np.abs(exc.x - GOAL) < 1e4)   # it had moved in
    assert "Try: a start nearer the data or a shorter duration; or raise the limits" in str(exc)
    assert "sosdyn.set_limits(max_rollout_calls=" in str(exc)


def test_a_rollout_over_its_time_budget_stops_within_it(monkeypatch):
    """On a fake clock where each field evaluation costs 1/64 s: with max_rollout_seconds = 1 the 65th
    evaluation is the first to end past the budget, and the next call stops the rollout before
    evaluating (66 calls counted, 65 evaluated), far from done (rtol 1e-12 over 1e6 s)."""
    step = 1 / 64                               # exact in binary: the clock reads 1.0 after 64 evaluations
    clock = [0.0]
    monkeypatch.setattr(time, "perf_counter", lambda: clock[0])

    def slow(X, goal):
        clock[0] += step
        return -(X - goal)

    with sd.limits(max_rollout_seconds=1), pytest.raises(WorkLimitError, match="max_rollout_seconds = 1") as info:
        rollout(slow, GOAL + 1.0, duration=1e6, dt=1e3, goal=GOAL, integrator="RK45", rtol=1e-12)
    assert clock[0] == info.value.seconds == 65 * step and info.value.calls == 66 and info.value.t < 1e6


def test_the_default_budget_lets_ordinary_rollouts_through():
    assert sd.get_limits().max_rollout_calls == 100_000 and sd.get_limits().max_rollout_seconds == 120
    traj = rollout(cubic, GOAL + 3.0, duration=10.0, dt=0.01, goal=GOAL)
    # x(t) - g = d / sqrt(1 + 2 d^2 t) for xdot = -(x - g)^3, d = 3
    np.testing.assert_allclose(traj.pos[-1] - GOAL, 3.0 / np.sqrt(1 + 2 * 9 * 10.0), rtol=1e-5)


@pytest.mark.parametrize("c", [1.0, 1e-6, 1e-9, 1e6])
def test_the_same_motion_in_any_units_has_the_same_relative_error(c):
    """xdot = -(x - g) in units where the numbers are c times larger: the relative error against
    the exact solution is the same for every c (with a fixed atol 1e-8 it was 6e-3 at c = 1e-9)."""
    x0, goal = np.array([4.0, 3.0]) * c, GOAL * c
    traj = rollout(lambda X, g: -(X - g), x0, duration=5.0, dt=0.01, goal=goal)
    exact = goal + (x0 - goal) * np.exp(-traj.t)[:, None]
    rel = np.abs(traj.pos - exact).max() / np.abs(x0 - goal).max()
    assert 1e-8 < rel < 2e-6, rel
    ref = rollout(lambda X, g: -(X - g), x0 / c, duration=5.0, dt=0.01, goal=goal / c)
    np.testing.assert_allclose(traj.pos / c, ref.pos, rtol=1e-9, atol=1e-12)


def test_motion_scale_and_explicit_tolerances():
    x0 = np.array([4.0, 3.0])
    events = parse_events([(1.0, [0.0, 9.0])], [(2.0, [1.0, 7.0])], 2, 5.0)
    assert motion_scale(x0, GOAL, events) == 9.0                    # the push is the largest move
    assert motion_scale(x0, GOAL, []) == 5.0 and motion_scale(GOAL, GOAL, []) == 1.0
    assert ATOL_REL == 1e-9
    for kw, match in ((dict(atol=0.0), "atol must be"), (dict(scale=-1.0), "scale must be")):
        with pytest.raises(InputError, match=match):
            rollout(cubic, x0, duration=1.0, dt=0.1, goal=GOAL, **kw)


def sliding(X, goal):
    """A field that switches across x2 = 0 (both sides point at the surface): the trajectory slides along
    it to the goal, x1 decaying like exp(-t / 10); an adaptive integrator crawls on the switch."""
    d = X - goal
    return np.column_stack([-0.1 * d[:, 0], -np.sign(d[:, 1]) * (1.0 + np.abs(d[:, 0]))])


def test_a_discontinuous_field_is_stopped_early_and_said_so():
    """Round 3 left a rollout from 1e6 data scales crawling along a switching surface (> 30,000 field
    calls, then max_rollout_calls); the jumps of the field are counted and stop it within a few thousand."""
    with pytest.raises(WorkLimitError, match=r"the field is discontinuous there: 1000 times its direction turned .* "
                                             r"Try: a start nearer the data; or a model that is smooth off the data, "
                                             r"gating='tempered'") as info:
        rollout(sliding, GOAL + np.array([50.0, 3.0]), duration=20.0, dt=0.1, goal=GOAL)
    assert info.value.calls < 5_000


def test_jumps_at_a_cheap_pace_are_a_sliding_mode_not_a_crawl():
    """A switched field that slides to its goal at little cost (CLF-DM's correction surface: 4,416 calls for
    5.8 s of 6.3 on LASA BendedLine) is not stopped by its jumps; the same jumps at a crawling pace are."""
    def jumps(meter, t_of):
        for k in range(2 * WorkMeter.MAX_JUMPS):
            meter.tick(t_of(k), np.zeros((1, 2)), GOAL)
            meter.seen(GOAL + 1.0 + 1e-9 * k, np.array([1.0, (-1.0) ** k]), GOAL)   # turns 90 deg every call
    cheap = WorkMeter(duration=10.0)
    jumps(cheap, lambda k: 0.004 * k)              # 2,000 calls for 8 s of 10: 2,500 at this pace
    assert cheap.jumps == 2 * WorkMeter.MAX_JUMPS - 1
    with pytest.raises(WorkLimitError, match="the field is discontinuous there: 1000 times"):
        jumps(WorkMeter(duration=10.0), lambda k: 1e-4 * k)     # 1,000 calls for 0.1 s: 100,000 at this pace


def test_a_posterior_model_far_from_its_data_stops_with_the_reason(linear_demos):
    model = sd.CDSP(n_components=3, field_degree=3, warp="none", gating="posterior").fit(linear_demos)
    x0 = model.goal_ + 1e6 * model.scale_ * np.array([np.cos(5.11), np.sin(5.11)])
    with pytest.raises(WorkLimitError, match="the field is discontinuous there") as info:
        model.rollout(x0, 60.0, dt=0.1)
    assert info.value.calls < 5_000                   # before: 100,001 calls (60,000 in 39 s measured)
    for gating in ("tempered", "smooth"):             # smooth: the default
        tempered = sd.CDSP(n_components=3, field_degree=3, warp="none", gating=gating).fit(linear_demos)
        end = tempered.rollout(x0, 60.0, dt=0.1).pos[-1]
        assert np.linalg.norm(end - tempered.goal_) < 1e-6 * tempered.scale_, gating


def test_smooth_fields_never_jump():
    for field, x0 in ((cubic, GOAL + 30.0), (lambda X, g: (X - g) @ np.array([[-1.0, 4.0], [-4.0, -1.0]]).T, GOAL + 5.0)):
        traj = rollout(field, x0, duration=10.0, dt=0.01, goal=GOAL, rtol=1e-10)
        assert np.all(np.isfinite(traj.pos))

"""The pose models' orientation block: its rate 0.5 / T and its settle zone (sosdyn.lfd.fit.pose, docs/theory.md
"Poses"): a speed floor only within goal_tol_deg of the goal, chosen as the least candidate rate with which the
reproductions and starts on the zone's edge arrive in time; the angle still never increases.
"""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sosdyn as sd
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.pose import PoseCDSP

from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit.floor import ARRIVAL, GOAL_FRACTION, floored
from sosdyn.lfd.fit.pose import ORIENTATION_GAMMA, edge_directions, orientation_params, settle_floor

RADIUS = np.deg2rad(20.0)
STARTS = np.deg2rad(80.0) * np.array([[1.0, 0, 0], [0, 0.6, 0.8], [-0.6, 0, 0.8], [0, -1.0, 0]])


def decaying_demos(rate=1.0, duration=6.0) -> Demonstrations:
    """r(t) = r0 e^{-rate t}: a demonstration per start (rotation vectors, goal 0)."""
    t = np.linspace(0.0, duration, 300)
    return Demonstrations([Demonstration(t, np.exp(-rate * t)[:, None] * r0, -rate * np.exp(-rate * t)[:, None] * r0,
                                         f"demo {i}") for i, r0 in enumerate(STARTS)], "settle", "rad")


def arrival_time(field, floor, r0, horizon) -> float:
    """First time the floored field's solution from r0 is within GOAL_FRACTION of the demos' box diagonal of 0
    (scipy's integrator, not sosdyn's Euler loop)."""
    demos = decaying_demos()
    X = demos.stacked()[0]
    tol = GOAL_FRACTION * np.linalg.norm(X.max(axis=0) - X.min(axis=0))
    rhs = (lambda t, r: field(r[None])[0]) if floor is None else \
        (lambda t, r: floored(r[None], field(r[None]), floor["rate"], floor["boost"], floor["radius"])[0])
    hit = lambda t, r: np.linalg.norm(r) - tol       # noqa: E731
    hit.terminal = True
    sol = solve_ivp(rhs, (0.0, horizon), r0, events=hit, rtol=1e-8, atol=1e-10, max_step=0.05)
    return float(sol.t_events[0][0]) if sol.t_events[0].size else np.inf


def test_a_field_that_crawls_near_the_goal_gets_a_settle_zone_that_makes_it_arrive():
    """f(r) = -r |r|^2 / (|r|^2 + 0.2^2) is about the demos' pace far out and crawls in the last degrees (rate
    |r|^2 / 0.2^2 there): the zone's least sufficient rate makes every edge start arrive within ARRIVAL x the
    demos' settling time, checked by an independent integrator; without it they do not."""
    field = lambda R: -R * (np.sum(R * R, axis=1, keepdims=True) / (np.sum(R * R, axis=1, keepdims=True) + 0.2**2))  # noqa: E731
    demos = decaying_demos()
    floor, arrivals = settle_floor(field, demos, RADIUS)
    assert floor is not None and floor["radius"] == pytest.approx(RADIUS)
    settle = np.log(np.deg2rad(80.0) / RADIUS)              # the demos enter the zone here; they end at 6 s
    budget = ARRIVAL * (6.0 - settle)
    edge = RADIUS * edge_directions()
    assert max(arrival_time(field, floor, r0, 4 * budget) for r0 in edge) <= budget * 1.02
    assert max(arrival_time(field, None, r0, 4 * budget) for r0 in edge) > budget
    assert arrivals["none"] > ARRIVAL


def test_a_field_that_arrives_in_time_gets_no_floor():
    floor, arrivals = settle_floor(lambda R: -3.0 * R, decaying_demos(), RADIUS)
    assert floor is None and arrivals["none"] <= ARRIVAL


def test_the_zone_keeps_the_angle_monotone_and_leaves_the_paths_alone():
    """|r| never increases along a floored solution (sigma >= 1 scales d|r|^2/dt), it settles far sooner than
    the field alone, and its path is the field's (a time change): for rdot = sigma A r with A the slow spiral
    below, r_3 / |r_12| stays constant and the turn of r_12 is 20 ln(|r_12(0)| / |r_12|), whatever sigma."""
    A = np.array([[-0.05, 1.0, 0.0], [-1.0, -0.05, 0.0], [0.0, 0.0, -0.05]])       # A + A^T = -0.1 I
    field = lambda R: R @ A.T       # noqa: E731
    r0 = 0.9 * RADIUS * np.array([0.6, 0.0, 0.8])
    sol = solve_ivp(lambda t, r: floored(r[None], field(r[None]), 2.0, 10.0, RADIUS)[0], (0, 20), r0, rtol=1e-10,
                    atol=1e-13, max_step=0.01)
    R = sol.y.T
    angle = np.linalg.norm(R, axis=1)
    assert np.all(np.diff(angle) <= 1e-12)
    assert angle[-1] < 0.5 * np.exp(-0.05 * 20.0) * angle[0]       # the field alone ends at e^{-0.05 t} of it
    planar = np.linalg.norm(R[:, :2], axis=1)
    np.testing.assert_allclose(R[:, 2] / planar, r0[2] / planar[0], rtol=1e-6)
    turn = -np.unwrap(np.arctan2(R[:, 1], R[:, 0]))                           # A turns r_12 clockwise
    np.testing.assert_allclose(turn - turn[0], 20.0 * np.log(planar[0] / planar), atol=1e-5)


def test_the_orientation_parameters():
    """Rate 0.5 / T unless gamma is given; the block's own floor "none" when left "auto" (the settle zone then),
    a given rate or "none" kept."""
    assert orientation_params({}, 10.0)["gamma"] == pytest.approx(ORIENTATION_GAMMA / 10.0)
    assert orientation_params({"gamma": 0.2}, 10.0)["gamma"] == 0.2
    assert orientation_params({}, 10.0)["speed_floor"] == "none"
    assert orientation_params({"speed_floor": 0.7}, 10.0)["speed_floor"] == 0.7
    assert orientation_params({"speed_floor": "none"}, 10.0)["speed_floor"] == "none"
    assert orientation_params({"metric": "learned"}, 10.0)["metric"] == "identity"


def test_too_many_settling_rollouts_are_refused_before_any_fit(monkeypatch):
    """The settle zone's rollouts (every demo's start and 14 edge starts) are counted against max_rollout_steps
    before either block is fitted, and the refusal names the remedies."""
    demos = sd.load_dataset("robottasks/openbox")

    def no_fit(self, data):
        raise AssertionError("a block was fitted")
    monkeypatch.setattr(CDSP, "fit", no_fit)
    with sd.limits(max_rollout_steps=1000), pytest.raises(sd.ResourceLimitError) as info:
        PoseCDSP().fit(demos)
    assert f"({len(demos) + 14} starts x" in str(info.value) and "speed_floor='none' or a rate" in str(info.value)

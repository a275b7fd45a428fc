"""Every public entry point that takes states refuses text, ragged lists, dicts, booleans and
complex numbers with an InputError and a hint (never numpy's ValueError / TypeError)."""
import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.lfd.runtime.states import (SPEED_KNEE, as_states, limit_speed, limit_speed_one, saturated_speed,
                                         saturated_speeds, speed_factor)

BAD = [
    (["a", "b"], "text|not numbers"),
    ("1,2", r"text '1,2'.*parse the text"),
    ([[1.0, 2.0], [3.0]], "not a rectangular array"),
    ({"x": 1.0, "y": 2.0}, r"is a dict.*d\['x'\]"),
    ([1 + 2j, 3.0], "complex"),
    (np.array([1.0 + 0j, 2.0]), "complex"),
    ([True, False], "booleans"),
    (None, "not a rectangular array"),
    ([1.0, None], "not a rectangular array"),
]


@pytest.mark.parametrize("value, message", BAD)
def test_as_states_refuses_with_a_hint(value, message):
    with pytest.raises(InputError, match=message) as info:
        as_states(value, 2)
    assert "Try:" in str(info.value)


@pytest.mark.parametrize("value, message", BAD)
def test_every_entry_point_refuses_with_a_hint(field_model, value, message):
    model = field_model
    step = model.predictor()
    calls = [lambda: model.predict(value), lambda: model.rollout(value, 1.0), lambda: step(value)]
    if value is not None:                                           # goal=None: the model's goal
        calls += [lambda: model.rollout(model.goal_, 1.0, goal=value), lambda: step(model.goal_, goal=value)]
    for call in calls:
        with pytest.raises(InputError, match=message):
            call()


def test_integers_and_lists_are_still_states(field_model):
    model = field_model
    x = [int(v) for v in np.round(model.goal_ + model.scale_)]
    np.testing.assert_allclose(model.predictor()(x), model.predict(np.array(x, float))[0], rtol=1e-12)
    with pytest.raises(InputError, match=r"one state of shape \(2,\)"):
        model.predictor()([x, x])


def test_limit_speed_scales_only_fast_rows():
    V = np.array([[3.0, 4.0], [0.3, 0.4], [0.0, 0.0]])
    # |v| = 5: rho = 5, y = 9, sigma = 0.5 + 0.5 / (1 + 9^-4)^(1/4) (closed form)
    sigma = 0.5 + 0.5 / (1 + 9.0 ** -4) ** 0.25
    np.testing.assert_allclose(limit_speed(V, 1.0), [[0.6 * sigma, 0.8 * sigma], [0.3, 0.4], [0.0, 0.0]], rtol=1e-15)
    assert limit_speed(V, None) is V


def test_the_speed_limit_is_smooth_bounded_and_identity_below_its_knee():
    """sigma(rho) = rho below SPEED_KNEE, increasing, below 1, and C^1 at least: the old
    min(1, v / |xdot|) had a kink at rho = 1 (sigma' jumped from 1 to 0) that stalled integrators."""
    rho = np.linspace(0.0, 6.0, 600_001)
    sigma = saturated_speeds(rho)
    h = rho[1] - rho[0]
    below = rho <= SPEED_KNEE
    np.testing.assert_array_equal(sigma[below], rho[below])
    assert np.all(np.diff(sigma) > 0) and sigma.max() < 1.0
    slope = np.diff(sigma) / h
    assert np.abs(np.diff(slope)).max() < 1e-4                     # no jump in sigma' anywhere (the kink: 1)
    assert np.abs(np.diff(slope, 2) / h).max() < 1e-1             # nor in sigma'' (C^2 and more)
    assert [saturated_speed(float(r)) for r in rho[::5000]] == pytest.approx(sigma[::5000], rel=1e-15)
    assert saturated_speed(np.inf) == 1.0 and saturated_speeds(np.array([np.inf]))[0] == 1.0


@pytest.mark.parametrize("scale", [1.0, 1e100, 1e155, 1e200, 1e300])
def test_the_speed_limit_does_not_overflow_far_away(scale):
    """|xdot|^2 overflowed from |xdot| ~ 1e154 and the limited field was exactly 0 (a rest point off
    the goal); scaled before squaring, the limited velocity keeps its direction at speed ~ max_speed."""
    V = np.array([[3.0, -4.0], [1.0, 1e-3]]) * scale
    for v_max in (1e-3, 0.4):
        L = limit_speed(V, v_max)
        one = np.array([limit_speed_one(v.tolist(), v_max) for v in V])
        speeds = np.linalg.norm(L, axis=1)
        assert np.all(np.isfinite(L)) and np.all(speeds > SPEED_KNEE * v_max)
        assert np.all(speeds <= v_max * (1 + 1e-15))
        np.testing.assert_allclose(L / speeds[:, None], V / np.linalg.norm(V / scale, axis=1)[:, None] / scale,
                                   rtol=1e-15)
        np.testing.assert_allclose(one, L, rtol=1e-15)
        np.testing.assert_allclose(V * speed_factor(V, v_max), L, rtol=1e-14)


def test_limit_speed_has_no_kink():
    """The limited speed as a function of the free speed s has a continuous slope: the former
    min(s, v) jumped from slope 1 to 0 at s = v, a kink on which an integrator crawled (issue 35:
    51,852 field calls where a limit 0.1 % lower took 1,409)."""
    u = np.array([0.6, -0.8])
    s = np.linspace(0.0, 4.0, 40_001)
    speed = np.linalg.norm(limit_speed(s[:, None] * u, 1.0), axis=1)
    slope = np.diff(speed) / np.diff(s)
    assert np.abs(np.diff(slope)).max() < 1e-3                    # the kink: a jump of 1
    assert speed.max() < 1.0 and np.all(np.diff(speed) > 0)       # below the limit, increasing

"""sosdyn.lfd.data.preprocess: each step against a known answer; LASA unchanged by the defaults."""
import numpy as np
import pytest

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.preprocess import (
    ALIGN_MAX, align_ends, blend_shift, noise_level, preprocess, rest_bounds, resample_uniform, smoothing_window)


def _arc(t, end=(1.0, 0.0)):
    """A smooth reach from (0, 1) to ``end`` (quarter circle plus a drift), sampled at t."""
    s = (t - t[0]) / (t[-1] - t[0])
    s = 3 * s**2 - 2 * s**3
    return np.column_stack([np.sin(s * np.pi / 2), np.cos(s * np.pi / 2)]) + np.outer(s, np.subtract(end, (1.0, 0.0)))


def test_noise_level_recovers_white_noise_sigma():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 2, 2000)
    demos = [Demonstration.from_positions(t, _arc(t) + 0.003 * rng.standard_normal((2000, 2)))]
    assert noise_level(demos) == pytest.approx(0.003, rel=0.08)
    assert noise_level([Demonstration.from_positions(t, _arc(t))]) < 1e-6


def test_smoothing_window_off_for_smooth_on_for_noisy_and_reduces_error():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 2, 200)
    clean = _arc(t)
    assert smoothing_window([Demonstration.from_positions(t, clean)]) is None
    noisy = Demonstrations([Demonstration.from_positions(t, clean + 0.002 * rng.standard_normal(clean.shape))])
    window = smoothing_window(noisy)
    assert window is not None and window % 2 == 1 and 5 <= window <= 200 // 4
    out, report = preprocess(noisy, trim_rest=False)
    assert report.window == window
    true_vel = np.gradient(clean, t, axis=0)
    before = np.abs(noisy[0].vel - true_vel)[5:-5].mean()
    after = np.abs(out[0].vel - true_vel)[5:-5].mean()
    assert after < 0.5 * before


def test_rest_bounds_keep_last_resting_start_and_first_resting_end():
    pos = np.array([[0, 0], [0, 0], [0.001, 0], [1, 0], [2, 0], [3, 0], [3.0005, 0], [3, 0]])
    assert rest_bounds(pos, 0.01) == (2, 5)
    assert rest_bounds(pos, 0.0) == (1, 7)          # exact repeats only (sample 6 differs from 7)


def test_resample_uniform_only_when_irregular():
    t = np.linspace(0, 1, 50)
    demo = Demonstration.from_positions(t, _arc(t))
    assert resample_uniform(demo) is demo
    t2 = np.sort(np.concatenate([t, [0.013, 0.517]]))
    out = resample_uniform(Demonstration.from_positions(t2, _arc(t2)))
    steps = np.diff(out.t)
    assert np.allclose(steps, steps[0]) and out.t[0] == 0 and out.t[-1] == pytest.approx(1.0)


def test_blend_shift_is_zero_before_the_blend_and_full_at_the_end():
    t = np.linspace(0, 2, 201)
    dx, dv = blend_shift(t, np.array([0.5, -1.0]), fraction=0.5)
    assert np.all(dx[:101] == 0) and np.allclose(dx[-1], [0.5, -1.0])
    inner = np.r_[1:100, 101:200]             # one-sided differences at the ends of the blend
    assert np.allclose(dv[inner], np.gradient(dx, t, axis=0)[inner], atol=1e-3)


def test_align_ends_moves_each_end_to_the_mean_and_reports_shifts():
    t = np.linspace(0, 1, 100)
    demos = Demonstrations([Demonstration.from_positions(t, _arc(t, e)) for e in ((1.0, 0.0), (1.2, 0.0))])
    out, shifts = align_ends(demos)
    assert np.allclose(shifts, [0.1, 0.1])
    assert np.allclose(out[0].pos[-1], [1.1, 0.0]) and np.allclose(out[1].pos[-1], [1.1, 0.0])
    assert np.array_equal(out[0].pos[:50], demos[0].pos[:50])


def test_align_ends_refuses_ends_too_far_apart_with_the_value_to_try():
    t = np.linspace(0, 1, 100)
    demos = Demonstrations([Demonstration.from_positions(t, _arc(t, e)) for e in ((1.0, 0.0), (1.0, 1.5))])
    with pytest.raises(DemonstrationError, match=r"more than max_shift.*Try: .*max_shift=0\.825"):
        align_ends(demos)
    assert ALIGN_MAX == 0.25
    align_ends(demos, max_shift=0.8)[0]


def test_preprocess_defaults_leave_lasa_unchanged(leaf):
    out, report = preprocess(leaf)
    assert report.window is None and not report.resampled and not np.any(report.shifts)
    for a, b in zip(leaf, out):
        assert np.array_equal(a.t, b.t) and np.array_equal(a.pos, b.pos) and np.array_equal(a.vel, b.vel)


@pytest.mark.parametrize("kwargs", [{"smooth_window": 4}, {"smooth_window": "yes"}, {"align": "maybe"}])
def test_preprocess_refuses_bad_options(leaf, kwargs):
    with pytest.raises(InputError):
        preprocess(leaf, **kwargs)

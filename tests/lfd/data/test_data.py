"""Demonstration containers, velocity estimates and the data checks."""

import numpy as np
import pytest

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations, check_demonstrations, estimate_velocity


def test_container_indexing_slicing_and_goal(demos):
    assert isinstance(demos[0], Demonstration)
    part = demos[1:]
    assert isinstance(part, Demonstrations) and len(part) == 2 and part.name == "lines"
    np.testing.assert_allclose(demos.goal, [0, 0], atol=1e-12)
    assert demos.dim == 2 and demos[0].duration == pytest.approx(2.0)
    with pytest.raises(DemonstrationError):
        Demonstrations([]).goal


def test_subsample_keeps_the_last_sample(demos):
    sub = demos.subsample(7)
    np.testing.assert_array_equal(sub[0].t, demos[0].t[[0, 7, 14, 21, 28, 35, 42, 49]])
    np.testing.assert_array_equal(sub[0].pos[-1], demos[0].pos[-1])
    for bad in (0, 1.5, True):
        with pytest.raises(InputError):
            demos.subsample(bad)


def test_container_rejects_non_demonstrations():
    with pytest.raises(InputError, match="not a Demonstration"):
        Demonstrations([np.zeros((10, 2))])


# ---------------------------------------------------------------- velocities


def test_savitzky_golay_is_exact_for_cubic_motion():
    t = np.linspace(0, 2, 40)
    pos = np.column_stack([t**3 - t, 2 * t**2])
    np.testing.assert_allclose(estimate_velocity(t, pos), np.column_stack([3 * t**2 - 1, 4 * t]), atol=1e-9)


def test_non_uniform_time_uses_second_order_differences():
    t = np.sort(np.random.default_rng(0).uniform(0, 1, 30))
    pos = np.column_stack([t**2, 3 * t])
    np.testing.assert_allclose(estimate_velocity(t, pos), np.column_stack([2 * t, 3 + 0 * t]), atol=1e-9)


def test_smoothing_reduces_noise():
    t = np.linspace(0, 1, 200)
    noisy = np.column_stack([t, -t]) + 1e-3 * np.random.default_rng(1).standard_normal((200, 2))
    smooth_err = np.abs(estimate_velocity(t, noisy) - [1, -1]).mean()
    raw_err = np.abs(np.gradient(noisy, t, axis=0) - [1, -1]).mean()
    assert smooth_err < 0.7 * raw_err  # Savitzky-Golay (9, 3) roughly halves the noise


def test_velocity_estimation_rejects_bad_time():
    with pytest.raises(DemonstrationError, match="strictly increasing"):
        estimate_velocity([0, 1, 1, 2], np.zeros((4, 1)))
    with pytest.raises(DemonstrationError, match="T >= 3"):
        estimate_velocity([0, 1], np.zeros((2, 1)))


# ---------------------------------------------------------------- checks


def replace(demo, **fields):
    values = {"t": demo.t, "pos": demo.pos, "vel": demo.vel, "source": demo.source} | fields
    return Demonstration(**values)


def test_check_accepts_good_data_and_keeps_name(demos):
    checked = check_demonstrations(demos)
    assert checked.name == "lines" and len(checked) == 3
    assert len(check_demonstrations(list(demos))) == 3


def test_nan_is_reported_with_demo_and_sample(demos):
    pos = demos[1].pos.copy()
    pos[5, 1] = np.nan
    with pytest.raises(DemonstrationError, match=r"demo 1: pos .*sample 5 of 50"):
        check_demonstrations([demos[0], replace(demos[1], pos=pos)])
    vel = demos[0].vel.copy()
    vel[7] = np.inf
    with pytest.raises(DemonstrationError, match=r"demo 0: vel .*sample 7"):
        check_demonstrations([replace(demos[0], vel=vel)])
    t = demos[0].t.copy()
    t[3] = np.nan
    with pytest.raises(DemonstrationError, match=r"time t is not finite .*sample 3"):
        check_demonstrations([replace(demos[0], t=t)])


def test_ragged_shapes(demos):
    d = demos[0]
    one_dim = replace(d, pos=d.pos[:, 0], vel=d.vel[:, 0])
    for bad in (replace(d, vel=d.vel[:-1]), replace(d, t=d.t[:-1]), one_dim):
        with pytest.raises(DemonstrationError, match="shapes do not fit"):
            check_demonstrations([bad])


def test_too_few_samples_and_non_increasing_time(demos):
    d = demos[0]
    with pytest.raises(DemonstrationError, match="only 9 samples"):
        check_demonstrations([replace(d, t=d.t[:9], pos=d.pos[:9], vel=d.vel[:9])])
    t = d.t.copy()
    t[20] = t[19]
    with pytest.raises(DemonstrationError, match=r"not strictly increasing at sample 20"):
        check_demonstrations([replace(d, t=t)])


def test_dimensions_must_agree(demos, make_line_demo):
    d3 = make_line_demo((1, 2, 3), goal=(0, 0, 0))
    with pytest.raises(DemonstrationError, match="demo 1 has dimension 3"):
        check_demonstrations([demos[0], d3])


def test_end_points_must_agree(demos, make_line_demo):
    far = make_line_demo((10, 5), goal=(4, 0), source="far.csv")
    with pytest.raises(DemonstrationError, match=r"demo 2 \(far.csv\).*ends 2\.667 mm"):
        check_demonstrations(Demonstrations([demos[0], demos[1], far], units="mm"))
    assert len(check_demonstrations([demos[0], far], goal_tol=np.inf)) == 2
    with pytest.raises(InputError, match="goal_tol"):
        check_demonstrations(demos, goal_tol=-1.0)


def test_accepted_goal_tol_is_kept_for_later_checks(demos, make_line_demo):
    """A set accepted with a larger goal_tol passes a second check without one (CDSP.fit re-checks)."""
    far = make_line_demo((10, 5), goal=(4, 0), source="far.csv")
    accepted = check_demonstrations([demos[0], far], goal_tol=3.0)
    assert accepted.goal_tol == 3.0 and accepted[:2].goal_tol == 3.0 and accepted.subsample(2).goal_tol == 3.0
    assert len(check_demonstrations(accepted)) == 2
    with pytest.raises(DemonstrationError, match="goal_tol = 1"):
        check_demonstrations(accepted, goal_tol=1.0)


def test_zero_demos_and_wrong_types():
    with pytest.raises(DemonstrationError, match="No demonstrations"):
        check_demonstrations([])
    with pytest.raises(InputError):
        check_demonstrations(42)
    with pytest.raises(DemonstrationError, match="not a numeric array"):
        Demonstration("abc", np.zeros((10, 2)), np.zeros((10, 2)))


# ---------------------------------------------------------------- files

"""sosdyn.lfd.data.crossing: a loop is found where it crosses; LASA shapes that do not cross pass."""
import numpy as np
import pytest

from sosdyn.lfd.data.crossing import crossing_warning, find_crossings
from sosdyn.lfd.data.demonstrations import Demonstration


def _loop(dim=2):
    """x = s^2 - 1, y = s (s^2 - 1) - 0.2 s, s in [-1.4, 1.4]: crosses itself once, at s = +-sqrt(1.2),
    i.e. (0.2, 0), with velocities (+-2 sqrt(1.2), 3 * 1.2 - 1.2)."""
    s = np.linspace(-1.4, 1.4, 400)
    pos = np.column_stack([s**2 - 1, s * (s**2 - 1) - 0.2 * s] + [np.zeros_like(s)] * (dim - 2))
    return Demonstration.from_positions(np.linspace(0, 4, 400), pos)


def test_a_loop_is_found_at_its_crossing_point():
    found = find_crossings([_loop()])
    assert len(found) == 1
    c = found[0]
    assert c.a == c.b == 0 and np.allclose(c.point, [0.2, 0.0], atol=1e-3)
    v1, v2 = np.array([2 * np.sqrt(1.2), 3 * 1.2 - 1.2]), np.array([-2 * np.sqrt(1.2), 3 * 1.2 - 1.2])
    expected = np.degrees(np.arccos(v1 @ v2 / (v1 @ v1)))
    assert c.angle_deg == pytest.approx(expected, abs=2.0)
    text = crossing_warning(found, "m")
    assert "demo 0 crosses itself at (0.2" in text and "cannot follow" in text


def test_a_3d_loop_is_a_near_pass():
    found = find_crossings([_loop(dim=3)])
    assert found and np.allclose(found[0].point, [0.2, 0.0, 0.0], atol=0.02)


def test_two_demos_meeting_head_on_cross_and_parallel_ones_do_not():
    t = np.linspace(0, 1, 100)
    a = Demonstration.from_positions(t, np.column_stack([t, 0.5 - t]))        # (0, .5) -> (1, -.5)
    b = Demonstration.from_positions(t, np.column_stack([1 - t, 0 * t]))       # (1, 0) -> (0, 0): 135 deg to a
    found = find_crossings([a, b], goal_radius=0.01)
    assert [(c.a, c.b) for c in found] == [(0, 1)] and np.allclose(found[0].point, [0.5, 0.0], atol=0.01)
    assert found[0].angle_deg == pytest.approx(135.0)
    c = Demonstration.from_positions(t, np.column_stack([t, 0.4 - t]))
    assert find_crossings([a, c], goal_radius=0.01) == []
    assert crossing_warning([]) is None


@pytest.mark.parametrize("shape", ["CShape", "BendedLine", "PShape", "Sshape", "Leaf_1", "Sine"])
def test_lasa_shapes_that_do_not_cross(shape):
    from sosdyn.lfd.data import lasa
    try:
        demos = lasa.load_lasa(shape)
    except Exception as exc:       # LASA data not installed
        pytest.skip(str(exc))
    assert find_crossings(demos) == []


def _reach_leaving_rest(offset=0.0):
    """A 3-D reach that first backs off its start by 1.5 % of its length, then goes out: it passes its
    start again in the opposite direction, within the rest ball at its start."""
    t = np.linspace(0.0, 2.0, 300)
    s = np.where(t < 0.3, -0.015 * np.sin(np.pi * t / 0.3), 0.0) + np.clip((t - 0.3) / 1.7, 0, 1) ** 2 * (3 - 2 * np.clip((t - 0.3) / 1.7, 0, 1))
    pos = np.column_stack([s, 0.3 * s ** 2, offset + 0.1 * s])
    return Demonstration.from_positions(t, pos)


def test_an_arm_leaving_rest_is_no_crossing():
    """Before: every demo of robottasks/openbox 'crossed itself' at its first sample (13 warnings on an
    ordinary reach): the rest at the ends is ignored, as the goal region is."""
    demos = [_reach_leaving_rest(), _reach_leaving_rest(0.002)]
    assert find_crossings(demos) == []
    assert find_crossings(demos, goal_radius=1e-4)               # the same hits, counted inside the rest ball


def test_openbox_reaches_do_not_cross():
    import warnings

    import sosdyn as sd
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        demos, _ = sd.preprocess(sd.load_dataset("robottasks/openbox", positions_only=True))
    assert find_crossings(demos) == []


def test_the_warning_is_a_count_and_the_first_few():
    t = np.linspace(0, 1, 100)
    a = Demonstration.from_positions(t, np.column_stack([t, 0.5 - t]))
    bs = [Demonstration.from_positions(t, np.column_stack([1 - t, 0 * t + k * 0.05])) for k in range(5)]
    found = find_crossings([a, *bs], goal_radius=0.01)
    text = crossing_warning(found)
    assert text.startswith(f"{len(found)} crossings involving 6 demonstrations; the first 3: demos 0 and 1 cross at")
    assert text.count(" cross at ") == 3 and "--order 2" in text

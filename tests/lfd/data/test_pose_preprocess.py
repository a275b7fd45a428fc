"""Preprocessing of pose demonstrations, both parts: resampling (slerp), rest trimming that keeps a rotation
in place, smoothing on the sphere, end alignment; each against the known curve it was made from."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.evaluation.poses import angles_deg
from sosdyn.lfd.data.pose_preprocess import preprocess_poses
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations

AXIS = np.array([0.3, -0.5, 0.81])


def curve(t):
    """A smooth pose motion: x along a bend, R turning 100 deg about AXIS (unit quaternions, w x y z)."""
    s = 0.5 - 0.5 * np.cos(np.pi * np.clip(t / t[-1], 0, 1))
    pos = np.column_stack([s, s ** 2, 0.3 * s])
    quat = Rotation.from_rotvec(np.deg2rad(100) * (1 - s)[:, None] * AXIS / np.linalg.norm(AXIS)).as_quat(
        scalar_first=True)
    return pos, quat


def test_jittered_stamps_are_resampled_by_slerp():
    rng = np.random.default_rng(0)
    t = np.cumsum(np.r_[0.0, 0.02 * (1 + 0.3 * rng.uniform(-1, 1, 199))])
    demos = PoseDemonstrations([PoseDemonstration(t, *curve(t / t[-1] * 4.0))] * 2, "jitter", "m")
    out, report = preprocess_poses(demos, smooth_window="off", trim_rest=False, align=False)
    d = out[0]
    assert report.position.resampled == [0, 1]
    np.testing.assert_allclose(np.diff(d.t)[:-1], np.median(np.diff(t)), rtol=1e-9, atol=1e-12)   # the last: to the end
    pos, quat = curve(d.t / t[-1] * 4.0)                          # the same curve at the new stamps
    assert np.abs(d.pos - pos).max() < 1e-3 and angles_deg(d.quat, quat).max() < 0.05
    np.testing.assert_allclose(np.linalg.norm(d.quat, axis=1), 1.0, atol=1e-12)


def test_rest_trimming_keeps_a_rotation_in_place():
    t = np.linspace(0.0, 5.0, 251)
    pos, quat = curve(np.linspace(0, 1, 101))
    rest = 50
    P = np.vstack([np.tile(pos[0], (rest + 50, 1)), pos, np.tile(pos[-1], (rest, 1))])   # turn in place, move, rest
    Q = np.vstack([np.tile(quat[0], (rest, 1)), Rotation.from_rotvec(np.linspace(0, 0.5, 50)[:, None] * [0, 0, 1]).__mul__(
        Rotation.from_quat(quat[0], scalar_first=True)).as_quat(scalar_first=True), np.tile(quat[-1], (101 + rest, 1))])
    P = P + 1e-6 * np.random.default_rng(1).normal(size=P.shape)       # a little noise to measure
    demos = PoseDemonstrations([PoseDemonstration(t, P, Q, "a"), PoseDemonstration(t, P, Q, "b")], "rest", "m")
    out, report = preprocess_poses(demos, smooth_window="off", align=False)
    start, end = report.position.trimmed[0]
    assert start == rest - 1                    # the turn in place is kept: only the rest before it goes
    assert end >= rest - 2 and len(out[0].t) == len(t) - start - end


def test_orientations_are_smoothed_on_the_sphere():
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 4.0, 400)
    pos, quat = curve(t)
    noisy = (Rotation.from_rotvec(np.deg2rad(0.3) * rng.normal(size=(len(t), 3))) *
             Rotation.from_quat(quat, scalar_first=True)).as_quat(scalar_first=True)
    demos = PoseDemonstrations([PoseDemonstration(t, pos + 1e-4 * rng.normal(size=pos.shape), noisy, str(i))
                                for i in range(3)], "noisy", "m")
    out, report = preprocess_poses(demos, trim_rest=False, align=False)
    assert report.position.window is not None
    before, after = angles_deg(noisy, quat), angles_deg(out[0].quat, quat)
    assert np.median(after) < np.median(before) / 3
    np.testing.assert_allclose(np.linalg.norm(out[0].quat, axis=1), 1.0, atol=1e-12)
    assert any("orientation noise" in line for line in report.lines("m"))


def test_ends_are_aligned_in_both_parts():
    t = np.linspace(0.0, 4.0, 200)
    pos, quat = curve(t)
    demos = []
    for i, (dx, angle) in enumerate([(0.02, 4.0), (-0.02, -4.0), (0.0, 0.0)]):
        tilt = Rotation.from_rotvec(np.deg2rad(angle) * np.linspace(0, 1, len(t))[:, None] * [1.0, 0, 0])
        demos.append(PoseDemonstration(t, pos + np.linspace(0, dx, len(t))[:, None] * [1, 0, 0],
                                       (Rotation.from_quat(quat, scalar_first=True) * tilt).as_quat(scalar_first=True),
                                       str(i)))
    demos = PoseDemonstrations(demos, "ends", "m")
    out, report = preprocess_poses(demos, smooth_window="off", trim_rest=False)
    ends = np.array([d.pos[-1] for d in out])
    np.testing.assert_allclose(ends, np.tile(ends.mean(axis=0), (3, 1)), atol=1e-12)
    assert max(angles_deg(d.quat[-1], out[2].quat[-1])[0] for d in out) < 1e-6
    for a, d in zip(out, demos):                  # starts untouched
        np.testing.assert_allclose(a.pos[0], d.pos[0], atol=1e-12)
        assert angles_deg(a.quat[0], d.quat[0])[0] < 1e-9
    assert max(report.turned_deg) == pytest.approx(4.0, abs=0.1)
    with pytest.raises(DemonstrationError, match="goal_tol_deg"):
        preprocess_poses(demos, goal_tol_deg=2.0)


def test_rest_jump_rest_is_refused_with_a_hint():
    t = np.linspace(0.0, 2.0, 40)
    pos = np.where(t[:, None] < 1.0, 0.0, 1.0) * np.array([1.0, 0, 0])
    quat = np.tile([1.0, 0, 0, 0], (40, 1))
    demos = PoseDemonstrations([PoseDemonstration(t, pos, quat, "jump")] * 2, "jump", "m")
    with pytest.raises(DemonstrationError, match="trim-rest off"):
        preprocess_poses(demos)
    with pytest.raises(InputError, match="smooth_window"):
        preprocess_poses(demos, smooth_window=4)

"""problems.robot: the control maths against hand-computed answers, the simulated arm's kinematics,
the commands of the methods, and the quick experiment (CDSP and PoseCDSP drive the Panda through a push and
a moved goal; the pose model also through a twist and a turned goal)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("pybullet", reason="the robot experiment needs the [robot] extra (pip install -e '.[robot]')")

from scipy.spatial.transform import Rotation  # noqa: E402

from problems.robot import arm, control, methods, run, tasks, trials  # noqa: E402 (after the skip)
from sosdyn.errors import InputError  # noqa: E402


def test_rotation_error_is_the_rotation_vector():
    quarter_z = [0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]      # 90 deg about z
    np.testing.assert_allclose(control.rotation_error(np.array([0, 0, 0, 1.0]), quarter_z),
                               [0, 0, math.pi / 2], atol=1e-12)
    np.testing.assert_allclose(control.rotation_error(np.array(quarter_z), quarter_z), 0, atol=1e-12)
    # q and -q are the same orientation: the error takes the short way (0, not 2 pi)
    np.testing.assert_allclose(control.rotation_error(-np.array(quarter_z), quarter_z), 0, atol=1e-12)


def test_joint_velocities_self_motion_leaves_the_task_alone():
    rng = np.random.default_rng(1)
    J, twist = rng.normal(size=(6, 7)), np.array([0.01, -0.02, 0.005, 0, 0, 0.01])
    lo, hi, big = -np.ones(7) * 3, np.ones(7) * 3, np.ones(7) * 100
    q = np.array([2.0, -1.5, 0.3, 0, 1, -2, 0.5])          # far from mid-range: the gradient acts
    with_limits = control.joint_velocities(J, twist, q, lo, hi, big, damping=1e-9)
    plain = control.joint_velocities(J, twist, q, lo, hi, big, damping=1e-9, k_limits=0.0)
    assert np.linalg.norm(with_limits - plain) > 0.01
    assert (with_limits - plain) @ control.limit_gradient(q, lo, hi) < 0      # H(q) decreases
    np.testing.assert_allclose(J @ with_limits, twist, atol=1e-9)
    np.testing.assert_allclose(J @ plain, twist, atol=1e-9)


def test_joint_velocities_guard_and_speed_cap():
    J = np.hstack([np.eye(6), np.zeros((6, 1))])
    lo, hi = -np.ones(7), np.ones(7)
    q = np.zeros(7)
    q[0] = lo[0] + 0.01                                   # inside the 2 deg guard
    qdot = control.joint_velocities(J, np.array([-1.0, 0, 0, 0, 0, 0]), q, lo, hi, np.ones(7) * 10,
                                    damping=0.0, k_limits=0.0)
    assert qdot[0] == 0.0                                 # may not move further towards the limit
    qdot = control.joint_velocities(J, np.array([40.0, 20, 0, 0, 0, 0]), np.zeros(7), lo, hi,
                                    np.ones(7) * 2, damping=0.0, k_limits=0.0)
    np.testing.assert_allclose(qdot[:2], [2.0, 1.0])      # scaled by 1/20: direction kept


class Field:                                              # xdot = -(x - goal), like a translated field
    def field(self, X, goal):
        return -(X - goal)


def test_position_command_holds_the_goal_orientation():
    goal = np.concatenate([[1.0, 2.0, 3.0], arm.wxyz(arm.DOWN)])
    tilted = (Rotation.from_rotvec([0.2, 0, 0]) * Rotation.from_quat(arm.DOWN)).as_quat()       # x y z w
    v, w = trials.position_command(lambda x, g: -(x - g))(np.zeros(3), arm.wxyz(tilted), goal)
    np.testing.assert_allclose(v, goal[:3])
    np.testing.assert_allclose(w, [-control.K_ORIENT * 0.2, 0, 0], atol=1e-12)      # turning back, world frame


def test_gmr_pose_step_turns_to_the_goal_and_keeps_both_limits():
    goal = np.concatenate([[1.0, 2.0, 3.0], Rotation.from_rotvec([0, 0, 0.3]).as_quat(scalar_first=True)])
    q = Rotation.from_rotvec([0, 0, 0.3 + 0.5]).as_quat(scalar_first=True)           # 0.5 rad past it about z
    v, w = methods.gmr_pose_step(Field(), Field(), 10.0, 10.0)(np.zeros(3), q, goal)
    np.testing.assert_allclose(v, goal[:3])
    np.testing.assert_allclose(w, [0, 0, -0.5], atol=1e-12)                           # rdot = -r about z
    v, w = methods.gmr_pose_step(Field(), Field(), 0.5, 0.1)(np.zeros(3), q, goal)
    a, b = np.linalg.norm(goal[:3]) / 0.5, 0.5 / 0.1                      # |v| / v_max, |omega| / w_max
    rho = max(a, b) * ((a / max(a, b)) ** 4 + (b / max(a, b)) ** 4) ** 0.25     # their joint ratio (4-norm)
    y = (rho - 0.5) / 0.5
    lam = (0.5 + 0.5 * y / (1 + y ** 4) ** 0.25) / rho                      # sigma(rho) / rho, the smooth limit
    np.testing.assert_allclose(np.concatenate([v, w]), lam * np.concatenate([goal[:3], [0, 0, -0.5]]), rtol=1e-12)
    assert np.linalg.norm(v) < 0.5 and np.linalg.norm(w) < 0.1


def test_time_to_goal_and_path_deviation():
    t = np.arange(6.0)
    assert trials.time_to_goal(t, np.array([3, 2, 0.5, 2, 0.5, 0.2]) < 1.0) == 4.0
    assert trials.time_to_goal(t, np.array([3, 2, 0.5, 0.4, 0.5, 1.2]) < 1.0) is None
    demo = np.column_stack([np.linspace(0, 1, 101), np.zeros(101), np.zeros(101)])
    assert trials.path_deviation(demo + [0, 0.003, 0.004], demo) == pytest.approx(0.005)


def test_workspace_shift_centres_the_box():
    raw = {"a": [(None, np.array([[10.0, -20, 30], [30, 0, 50]]), None)], "b": [(None, np.array([[20.0, 20, 40]]), None)]}
    shift = tasks.workspace_shift(raw)                    # box centre (0.2, 0, 0.4) m
    np.testing.assert_allclose(shift, tasks.WORKSPACE_CENTRE - [0.2, 0.0, 0.4], atol=1e-12)


def test_panda_jacobian_and_inverse_kinematics():
    sim = arm.PandaSim()
    try:
        q, err = sim.solve_ik([0.45, -0.1, 0.3])
        assert err < 1e-4 and np.all((q > sim.lo) & (q < sim.hi))
        x0, quat = sim.ee()
        assert np.degrees(np.linalg.norm(control.rotation_error(quat, arm.DOWN))) < 0.1
        dq = 1e-3 * np.array([1, -2, 1, 3, -1, 2, 1.0])  # pybullet's poses are float32: no tinier steps
        sim.reset(q + dq)
        moved, predicted = sim.ee()[0] - x0, (sim.jacobian(q) @ dq)[:3]
        assert np.linalg.norm(moved - predicted) < 0.01 * np.linalg.norm(predicted)
    finally:
        sim.close()


def test_output_is_checked_before_any_trial(tmp_path):
    (tmp_path / "taken").write_text("results of yesterday")
    with pytest.raises(InputError, match="is a file"):
        run.main(["--quick", "--out", str(tmp_path / "taken")])
    assert (tmp_path / "taken").read_text() == "results of yesterday"


@pytest.mark.slow
def test_quick_experiment(tmp_path):
    results = run.run(tmp_path, quick=True)
    saved = json.loads((tmp_path / "results.json").read_text())
    fits = saved["meta"]["fits"]
    assert saved["meta"]["simulator"].startswith("pybullet") and fits["openbox/CDSP"]["certified"]
    assert fits["openbox/PoseCDSP"]["certified"]
    assert {r["method"] for r in saved["trials"]} == {"CDSP", "GMR", "PoseCDSP", "GMR pose"}   # baselines beside
    for name, pose in (("CDSP", False), ("PoseCDSP", True)):
        mine = [r for r in results["trials"] if r["method"] == name]
        assert len(mine) == 2 and all(r["push"] and r["goal_moved"] and r["pose"] == pose for r in mine)
        for r in mine:                            # within 5 mm and 2 deg of the moved goal pose, no limit hit
            assert r["success"] and r["final_pos_err_m"] < trials.TOL and r["final_ori_err_deg"] < trials.ORI_TOL_DEG
            assert not r["joint_limit_hit"] and r["peak_commanded_joint_speed_rad_s"] <= arm.QDOT_MAX.max() + 1e-9
    twisted = [r["push_turn_deg"] for r in results["trials"] if r["method"] == "PoseCDSP"]
    assert min(twisted) > 10.0                    # the pushes did twist the gripper
    for name in ("index.html", "figures/frames.png", "figures/frames_pose.png", "figures/angles.png"):
        assert (tmp_path / name).is_file(), name

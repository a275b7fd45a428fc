"""problems.robot: the control maths against hand-computed answers, the simulated arm's kinematics,
and the quick experiment (CDSP drives the Panda through a push and a moved goal)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("pybullet", reason="the robot experiment needs the [robot] extra (pip install -e '.[robot]')")

from problems.robot import arm, control, run, tasks, trials  # noqa: E402 (after the skip)


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


def test_gmr_step_moves_with_the_goal_and_keeps_the_speed_limit():
    class Field:                                          # xdot = -(x - goal), like a translated field
        def field(self, X, goal):
            return -(X - goal)
    goal = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(run.gmr_step(Field(), 10.0, np.zeros(3), goal), goal)
    y = (2.0 / 0.5 - 0.5) / 0.5                          # |xdot| = 2 = 4 x the limit: the smooth limit's speed
    speed = 0.5 * (0.5 + 0.5 * y / (1 + y ** 4) ** 0.25)  # 0.5 sigma(4), just below the limit
    np.testing.assert_allclose(run.gmr_step(Field(), 0.5, np.array([1.0, 2.0, 1.0]), goal), [0, 0, speed], rtol=1e-15)


def test_time_to_goal_and_path_deviation():
    t = np.arange(6.0)
    assert trials.time_to_goal(t, np.array([3, 2, 0.5, 2, 0.5, 0.2]), 1.0) == 4.0
    assert trials.time_to_goal(t, np.array([3, 2, 0.5, 0.4, 0.5, 1.2]), 1.0) is None
    demo = np.column_stack([np.linspace(0, 1, 101), np.zeros(101), np.zeros(101)])
    assert trials.path_deviation(demo + [0, 0.003, 0.004], demo) == pytest.approx(0.005)


def test_workspace_shift_centres_the_box():
    raw = {"a": [(None, np.array([[10.0, -20, 30], [30, 0, 50]]))], "b": [(None, np.array([[20.0, 20, 40]]))]}
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


@pytest.mark.slow      # experiment-sized: make test-slow
def test_quick_experiment(tmp_path):
    results = run.run(tmp_path, quick=True)
    saved = json.loads((tmp_path / "results.json").read_text())
    assert saved["meta"]["simulator"].startswith("pybullet") and saved["meta"]["fits"]["openbox/CDSP"]["certified"]
    assert {r["method"] for r in saved["trials"]} == {"CDSP", "GMR"}            # the baseline beside it
    cdsp = [r for r in results["trials"] if r["method"] == "CDSP"]
    assert len(cdsp) == 2 and all(r["push"] and r["goal_moved"] for r in cdsp)
    for r in cdsp:                                        # within 5 mm of the moved goal, no limit hit
        assert r["success"] and r["final_pos_err_m"] < trials.TOL and not r["joint_limit_hit"]
        assert r["peak_commanded_joint_speed_rad_s"] <= arm.QDOT_MAX.max() + 1e-9
    assert (tmp_path / "index.html").is_file() and (tmp_path / "figures" / "frames.png").is_file()

"""PoseCDSP against a known answer: xdot = -k (x - x_g), rdot = -k r in the chart at R_g.

For this system |x - x_g|^2 and |r|^2 are contraction metrics at rate 2k (the Jacobians are -k I), every
trajectory reaches the goal pose, and the solution is known in closed form:
x(t) = x_g + e^{-kt} (x0 - x_g), R(t) = R_g exp(e^{-kt} r0). The cascade's properties (the position never
moves for an orientation-only start or a goal turn; the angle never increases; every start up to 180 deg
converges) are checked on rollouts, in Python and in the exported C++.
"""
import re
import shutil
import subprocess

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sosdyn.errors import InputError, ModelFileError
from sosdyn.evaluation.poses import angles_deg, turned
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations, chart
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.files import load_model, load_pose_model
from sosdyn.lfd.model.pose import PoseCDSP
from sosdyn.lfd.runtime.pose import body_velocity, pose_to_cpp, pose_to_python

K_RATE = 0.8
X_GOAL = np.array([0.4, -0.2, 0.3])
R_GOAL = Rotation.from_rotvec([0.3, -0.5, 0.2])
Q_GOAL = R_GOAL.as_quat(scalar_first=True)
_RNG = np.random.default_rng(3)
#: 8 starts: straight-line demos s(t) = e^{-kt} s0 span R^6 only with >= 6 independent starts.
STARTS = [(X_GOAL + 0.4 * _RNG.normal(size=3), 1.2 * _RNG.uniform(-1, 1, size=3)) for _ in range(8)]


def exact(x0, r0, t):
    decay = np.exp(-K_RATE * t)[:, None]
    return X_GOAL + decay * (x0 - X_GOAL), (R_GOAL * Rotation.from_rotvec(decay * r0)).as_quat(scalar_first=True)


@pytest.fixture(scope="module")
def fitted():
    t = np.linspace(0.0, 12.0, 240)
    demos = PoseDemonstrations([PoseDemonstration(t, *exact(x0, r0, t), f"start {i}")
                                for i, (x0, r0) in enumerate(STARTS)], "known", "m")
    return PoseCDSP(n_components=1, warp="none", max_samples=400).fit(demos)


def test_known_system_certified_and_converges(fitted):
    assert fitted.certified_ and fitted.verify().passed
    assert angles_deg(fitted.goal_quat_, Q_GOAL)[0] < 0.01        # demos end 0.005 deg short
    x0, r0 = np.array([0.2, 0.2, 0.6]), np.array([0.4, 0.8, -0.6])      # a start of no demo
    traj = fitted.rollout(np.concatenate([x0, (R_GOAL * Rotation.from_rotvec(r0)).as_quat(scalar_first=True)]),
                          12.0, dt=0.05)
    x_true, q_true = exact(x0, r0, traj.t)
    np.testing.assert_allclose(np.linalg.norm(traj.quat, axis=1), 1.0, atol=1e-12)       # on the sphere
    assert angles_deg(traj.quat, q_true).max() < 1.0                     # follows the true rotation
    assert np.abs(traj.pos - x_true).max() < 0.01
    assert angles_deg(traj.quat[-1], Q_GOAL)[0] < 1.0                    # geodesic error at the end
    assert "certified=True" in repr(fitted) and "orientation: K=1" in repr(fitted)


AXES = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, -0.48, 0.64]])


@pytest.mark.parametrize("angle", [90.0, 170.0, 179.0, 180.0])
def test_orientation_only_start_never_moves_the_position(fitted, angle):
    """At the goal position, turned up to a half turn: the position stays exactly put (the cascade), the
    angle to the goal never increases and reaches the goal; no refusal."""
    g, q = fitted.goal_pos_, fitted.goal_quat_
    for axis in AXES:
        traj = fitted.rollout(np.concatenate([g, turned(q, angle, axis)]), 30.0, dt=0.05)
        assert np.abs(traj.pos - g).max() == 0.0
        a = angles_deg(traj.quat, q)
        assert a[0] == pytest.approx(angle, abs=1e-6) and a[-1] < 0.1
        assert np.all(np.diff(a) <= 1e-9)


def test_goal_turn_never_moves_the_position(fitted):
    g, q = fitted.goal_pos_, fitted.goal_quat_
    for axis in AXES:
        new = np.concatenate([g, turned(q, 30.0, axis)])
        traj = fitted.rollout(np.concatenate([g, q]), 20.0, dt=0.05, goal_changes=[(2.0, new)])
        assert np.abs(traj.pos - g).max() == 0.0 and angles_deg(traj.quat[-1], new[3:])[0] < 0.1


def test_far_starts_converge_and_the_angle_is_monotone(fitted):
    rng = np.random.default_rng(7)
    for _ in range(6):
        axis, angle = rng.normal(size=3), rng.uniform(150.0, 179.9)
        p0 = np.concatenate([X_GOAL + 0.5 * rng.normal(size=3), turned(fitted.goal_quat_, angle, axis)])
        traj = fitted.rollout(p0, 30.0, dt=0.05)
        a = angles_deg(traj.quat, fitted.goal_quat_)
        assert np.all(np.diff(a) <= 1e-9) and a[-1] < 0.1
        assert np.linalg.norm(traj.pos[-1] - fitted.goal_pos_) < 1e-3
        bound = fitted.excursion_bound(p0)                  # the position block's certified reach
        assert np.linalg.norm(traj.pos - fitted.goal_pos_, axis=1).max() <= bound * (1 + 1e-9)


def test_predictor_gives_world_angular_velocity(fitted):
    x0, r0 = np.array([0.5, 0.0, 0.2]), np.array([0.3, -0.7, 0.5])
    q0 = (R_GOAL * Rotation.from_rotvec(r0)).as_quat(scalar_first=True)
    v, w = fitted.predictor()(x0, q0)
    h = 1e-5                                                             # the known answer, differentiated
    x1, q1 = exact(x0, r0, np.array([h]))
    np.testing.assert_allclose(v, (x1[0] - x0) / h, atol=2e-3)
    w_true = (Rotation.from_quat(q1[0], scalar_first=True) * Rotation.from_quat(q0, scalar_first=True).inv()
              ).as_rotvec() / h
    np.testing.assert_allclose(w, w_true, atol=2e-3)
    goal = np.concatenate([fitted.goal_pos_ + 1.0, fitted.goal_quat_])  # a moved goal: translated field
    v2, w2 = fitted.predictor(goal=goal)(x0 + 1.0, q0)
    np.testing.assert_allclose(np.concatenate([v2, w2]), np.concatenate([v, w]), atol=1e-12)


def test_body_velocity_matches_the_exponential():
    rng = np.random.default_rng(0)
    rs = np.array([rng.normal(size=3), 1e-6 * rng.normal(size=3), 2.9 * np.array([0.0, 0.6, 0.8])])
    ds, h = rng.normal(size=(3, 3)), 1e-6
    body = (Rotation.from_rotvec(rs).inv() * Rotation.from_rotvec(rs + h * ds)).as_rotvec() / h
    np.testing.assert_allclose(body_velocity(rs, ds), body, atol=1e-5)       # all rows at once


def test_goal_change_and_push(fitted):
    p0 = np.concatenate([X_GOAL + 0.2, Q_GOAL])
    turned = Rotation.from_rotvec([0, 0, 0.6]) * R_GOAL
    goal2 = np.concatenate([X_GOAL - 0.1, turned.as_quat(scalar_first=True)])
    traj = fitted.rollout(p0, 20.0, dt=0.05, perturbations=[(2.0, [0.1, 0, 0, 0.3, 0, 0])], goal_changes=[(6.0, goal2)])
    assert np.all(np.diff(traj.t) > 0)
    assert angles_deg(traj.quat[-1], goal2[3:])[0] < 0.1 and np.linalg.norm(traj.pos[-1] - goal2[:3]) < 1e-3


BAD_QUATS = [[0, 0, 0, 0], [np.nan, 0, 0, 1], [np.inf, 0, 0, 0], [100, 0, 0, 0], [1, 0, 0]]


def test_bad_poses_refused(fitted):
    with pytest.raises(InputError, match="unknown parameters \\['n_comp'\\]"):
        PoseCDSP(n_comp=3)
    with pytest.raises(InputError, match="goal_tol_deg"):
        PoseCDSP(goal_tol_deg=200)
    with pytest.raises(InputError, match="7 finite numbers"):
        fitted.rollout([0, 0, 0], 1.0)
    step, x = fitted.predictor(), np.zeros(3)
    for q in BAD_QUATS:                              # the predictor and the rollout refuse alike, typed
        with pytest.raises(InputError, match="not a finite unit 4-vector"):
            step(x, q)
        with pytest.raises(InputError):
            fitted.rollout(np.concatenate([x, q]) if len(q) == 4 else [0] * 6, 1.0)
        with pytest.raises(InputError):
            step(x, Q_GOAL, goal=np.concatenate([x, q]) if len(q) == 4 else np.zeros(6))
        if len(q) == 4:                              # a goal change's quaternion: its own message
            with pytest.raises(InputError, match="goal change(: the quaternion| must be 7 finite numbers)"):
                fitted.rollout(np.concatenate([x, Q_GOAL]), 1.0, goal_changes=[(0.5, np.concatenate([x, q]))])
    with pytest.raises(InputError):
        step([np.nan, 0, 0], Q_GOAL)


def test_save_load_round_trip(fitted, tmp_path):
    path = fitted.save(tmp_path / "pose.json")
    x, q = np.array([0.5, 0.1, 0.2]), Rotation.from_rotvec([0.1, 0.2, 0.3]).as_quat(scalar_first=True)
    for loaded in (load_pose_model(path), load_model(path)):        # load_model dispatches on the format
        assert isinstance(loaded, PoseCDSP) and loaded.certified_
        np.testing.assert_allclose(np.concatenate(loaded.predictor()(x, q)),
                                   np.concatenate(fitted.predictor()(x, q)), rtol=1e-12, atol=1e-14)
    fitted.position_.save(tmp_path / "chart.json")                 # a position model file is not a pose file
    with pytest.raises(ModelFileError, match="not a sosdyn-pose file"):
        load_pose_model(tmp_path / "chart.json")
    assert isinstance(load_model(tmp_path / "chart.json"), CDSP)


def _forged(path, edit):
    """The pose file at ``path`` with ``edit`` applied to its content and the checksum recomputed."""
    import json

    from sosdyn.lfd.model.fileformat import CHECKSUM, _digest
    doc = json.loads(path.read_text())
    edit(doc)
    doc[CHECKSUM] = _digest(doc)
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["goal_quat"].__setitem__(3, None), "goal_quat must hold numbers"),
    (lambda d: d.__setitem__("rot_factor", 1e308), "unknown field rot_factor"),
    (lambda d: d["still"].__setitem__("orientation", -1.0), "still.orientation must be a positive number"),
    (lambda d: d["orientation"]["params"].__setitem__("metric", "learned"), "identity metric"),
    (lambda d: d["orientation"]["state"].__setitem__("goal_", [0.1, 0.0, 0.0]), "goal 0"),
    (lambda d: d["orientation"]["state"]["W_"][1][1].__setitem__(0, 4.0), "identity metric|does not check out"),
    (lambda d: d.__setitem__("version", 1), "older sosdyn"),
])
def test_forged_pose_files_refused(fitted, tmp_path, edit, message):
    path = _forged(fitted.save(tmp_path / "pose.json"), edit)
    with pytest.raises(ModelFileError, match=message):
        load_model(path)


V_MAX, W_MAX = 0.1, 0.3          # m/s and rad/s: both active at the start below (|v| ~ 0.4, |omega| ~ 1)


def test_speed_limits_scale_v_and_omega_by_one_factor(fitted):
    x0, r0 = X_GOAL + np.array([0.4, -0.3, 0.2]), np.array([0.9, -0.6, 0.5])
    q0 = (R_GOAL * Rotation.from_rotvec(r0)).as_quat(scalar_first=True)
    free, limited = fitted.predictor(), fitted.predictor(max_speed=V_MAX, max_angular_speed=W_MAX)
    for scale in (1.0, 0.3, 0.02):                 # both limits active, one, none (near the goal)
        x, q = X_GOAL + scale * (x0 - X_GOAL), (R_GOAL * Rotation.from_rotvec(scale * r0)).as_quat(scalar_first=True)
        v, w = free(x, q)
        rho = ((np.linalg.norm(v) / V_MAX) ** 4 + (np.linalg.norm(w) / W_MAX) ** 4) ** 0.25    # the joint ratio
        y = (rho - 0.5) / 0.5
        lam = 1.0 if rho <= 0.5 else (0.5 + 0.5 * y / (1 + y ** 4) ** 0.25) / rho             # smooth, < 1 / rho
        vl, wl = limited(x, q)
        np.testing.assert_allclose(np.concatenate([vl, wl]), lam * np.concatenate([v, w]), rtol=1e-12, atol=1e-15)
        assert np.linalg.norm(vl) <= V_MAX * (1 + 1e-12) and np.linalg.norm(wl) <= W_MAX * (1 + 1e-12)
    assert min(V_MAX / np.linalg.norm(free(x0, q0)[0]), W_MAX / np.linalg.norm(free(x0, q0)[1])) < 0.5
    with pytest.raises(InputError, match="max_angular_speed must be a finite number > 0 \\(rad/s\\)"):
        fitted.predictor(max_angular_speed=-1.0)


def test_speed_limited_rollout_keeps_the_path_and_the_goal(fitted):
    x0, r0 = X_GOAL + np.array([0.4, -0.3, 0.2]), np.array([0.9, -0.6, 0.5])
    p0 = np.concatenate([x0, (R_GOAL * Rotation.from_rotvec(r0)).as_quat(scalar_first=True)])
    free = fitted.rollout(p0, 12.0, dt=0.002)                  # dense: the gap below is not its sampling
    slow = fitted.rollout(p0, 40.0, dt=0.02, max_speed=V_MAX, max_angular_speed=W_MAX)
    dt = np.diff(slow.t)
    speed = np.linalg.norm(np.diff(slow.pos, axis=0), axis=1) / dt
    turn = np.deg2rad(angles_deg(slow.quat[1:], slow.quat[:-1])) / dt
    assert speed.max() <= V_MAX * 1.01 and turn.max() <= W_MAX * 1.01
    assert speed[:10].min() > 0.5 * V_MAX or turn[:10].min() > 0.9 * W_MAX          # a limit is active
    s_free, s_slow = (np.hstack([tr.pos, chart(tr.quat, Q_GOAL)]) for tr in (free, slow))
    gap = np.min(np.linalg.norm(s_slow[::20, None] - s_free[None], axis=2), axis=1)   # distance to the free path
    assert gap.max() < 0.002 * np.linalg.norm(s_free[0] - s_free[-1])     # per-block limits: 0.07
    assert np.linalg.norm(slow.pos[-1] - X_GOAL) < 1e-3 and angles_deg(slow.quat[-1], Q_GOAL)[0] < 0.1
    assert slow.t[np.argmax(np.linalg.norm(slow.pos - X_GOAL, axis=1) < 0.05)] > \
        free.t[np.argmax(np.linalg.norm(free.pos - X_GOAL, axis=1) < 0.05)] + 2.0     # arrives later


@pytest.mark.parametrize("limits", [(None, None), (V_MAX, W_MAX), (None, W_MAX)])
def test_python_export_returns_the_same_velocities(fitted, limits):
    namespace = {}
    exec(compile(pose_to_python(fitted, *limits), "pose_model.py", "exec"), namespace)
    rng = np.random.default_rng(1)
    step = fitted.predictor(max_speed=limits[0], max_angular_speed=limits[1])
    for goal in (None, np.concatenate([fitted.goal_pos_ - 0.3, Rotation.from_rotvec([0.2, 0, 0.4]).as_quat(
            scalar_first=True)])):
        for _ in range(3):
            x, q = rng.normal(size=3), Rotation.from_rotvec(rng.uniform(-1, 1, 3)).as_quat(scalar_first=True)
            np.testing.assert_allclose(np.concatenate(namespace["predict_pose"](x, q, goal)),
                                       np.concatenate(step(x, q, goal)), rtol=1e-12, atol=1e-14)


def test_cdsp_points_pose_demos_to_posecdsp():
    t = np.linspace(0.0, 1.0, 20)
    demos = PoseDemonstrations([PoseDemonstration(t, *exact(*STARTS[0], t))])
    with pytest.raises(InputError, match="PoseCDSP"):
        CDSP().fit(demos)


CPP_MAIN = """#include <cstdio>
#include "pose.hpp"
int main() {
  double in[14], v[3], w[3];
  while (std::scanf("%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", in, in + 1, in + 2, in + 3, in + 4,
                    in + 5, in + 6, in + 7, in + 8, in + 9, in + 10, in + 11, in + 12, in + 13) == 14) {
    const bool ok = NAMESPACE::predict_pose(in, in + 3, v, w, in[7] == 0 ? nullptr : in + 7);
    std::printf("%.17g %.17g %.17g %.17g %.17g %.17g %d\\n", v[0], v[1], v[2], w[0], w[1], w[2], ok ? 1 : 0);
  }
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
@pytest.mark.parametrize("limits, namespace, pose_ns", [((None, None), "pose_model", "pose_model_pose"),
                                                       ((V_MAX, W_MAX), "arm_", "arm_pose")])
def test_cpp_export_returns_the_same_velocities(fitted, tmp_path, limits, namespace, pose_ns):
    """The header's predict_pose gives the predictor's (v, omega); any valid namespace, one ending in _ too,
    names no reserved identifier (none with a double underscore)."""
    source = pose_to_cpp(fitted, namespace, max_speed=limits[0], max_angular_speed=limits[1])
    assert not re.search(r"[A-Za-z0-9_]*__[A-Za-z0-9_]*", source.replace("__cplusplus", ""))
    (tmp_path / "pose.hpp").write_text(source)
    (tmp_path / "main.cpp").write_text(CPP_MAIN.replace("NAMESPACE", pose_ns))
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(tmp_path / "main"),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    rng = np.random.default_rng(2)
    goal = np.concatenate([fitted.goal_pos_ + 0.2, Rotation.from_rotvec([0, 0.3, 0.1]).as_quat(scalar_first=True)])
    rows, expected = [], []
    for g in (None, goal):
        for _ in range(4):
            x, q = rng.normal(size=3), Rotation.from_rotvec(rng.uniform(-1.5, 1.5, 3)).as_quat(scalar_first=True)
            q = q if rng.random() < 0.5 else -q                        # either sign of the same rotation
            rows.append(np.concatenate([x, q, np.zeros(7) if g is None else g]))
            expected.append(np.concatenate(fitted.predictor(max_speed=limits[0], max_angular_speed=limits[1])(x, q, g)))
    for angle in (170.0, 179.0, 179.99):                          # near the cut locus: a velocity, as in Python
        q = turned(fitted.goal_quat_, angle, [0.3, -0.4, 0.5])
        rows.append(np.concatenate([fitted.goal_pos_, q, np.zeros(7)]))
        expected.append(np.concatenate(fitted.predictor(max_speed=limits[0], max_angular_speed=limits[1])(
            fitted.goal_pos_, q)))
    rows.append(np.concatenate([np.zeros(3), [0.0, 0.0, 0.0, 0.0], np.zeros(7)]))     # a zero quaternion
    res = subprocess.run([str(tmp_path / "main")], input="\n".join(" ".join(repr(float(v)) for v in r) for r in rows),
                         capture_output=True, text=True, check=True)
    out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    assert (out[:-1, -1] == 1).all() and out[-1, -1] == 0
    np.testing.assert_allclose(out[:-1, :6], np.array(expected), rtol=1e-10, atol=1e-12)


def test_a_pose_model_through_a_twist_keeps_its_bound_file_and_export(tmp_path):
    """The known system with the position block through a fitted twist (and no bump; the orientation block
    never has a warp): certified, the angle never increases along a rollout, the file round-trips and the
    export agrees."""
    t = np.linspace(0.0, 12.0, 240)
    demos = PoseDemonstrations([PoseDemonstration(t, *exact(x0, r0, t), f"start {i}")
                                for i, (x0, r0) in enumerate(STARTS)], "known", "m")
    m = PoseCDSP(n_components=1, warp={"n_maps": 0, "twist": 2.0}, max_samples=400).fit(demos)
    assert m.certified_ and "twist" in m.position_.warp_ and m.orientation_.warp_ is None and m.verify().passed
    r0 = 2.0 * np.array([0.6, 0.0, 0.8])
    p0 = np.concatenate([X_GOAL + 0.3, (R_GOAL * Rotation.from_rotvec(r0)).as_quat(scalar_first=True)])
    traj = m.rollout(p0, 10.0, dt=0.05)
    a = angles_deg(traj.quat, m.goal_quat_)
    assert np.all(np.diff(a) <= 1e-9) and a[-1] < 1.0
    x, q = np.array([0.5, 0.1, 0.2]), Rotation.from_rotvec([0.1, 0.2, 0.3]).as_quat(scalar_first=True)
    loaded = load_model(m.save(tmp_path / "twisted_pose.json"))
    np.testing.assert_allclose(np.concatenate(loaded.predictor()(x, q)), np.concatenate(m.predictor()(x, q)),
                               rtol=1e-12, atol=1e-14)
    namespace = {}
    exec(compile(pose_to_python(m), "pose_model.py", "exec"), namespace)
    np.testing.assert_allclose(np.concatenate(namespace["predict_pose"](x, q, None)),
                               np.concatenate(m.predictor()(x, q)), rtol=1e-12, atol=1e-14)

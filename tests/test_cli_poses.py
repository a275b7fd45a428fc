"""``sosdyn fit`` / ``export`` / ``plot`` on pose CSVs (either quaternion order): a certified pose model
and a standalone evaluator whose (v, omega) equal the model's."""
from __future__ import annotations

import re
import importlib.util
import shutil
import subprocess

import numpy as np
import pytest
from cli_support import assert_one_error_line, run
from scipy.spatial.transform import Rotation

from sosdyn.evaluation.poses import angles_deg
from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.lfd.data.files import load_demos
from sosdyn.lfd.data.pose import PoseDemonstrations
from sosdyn.lfd.model.files import load_model


def write_pose_csvs(folder, n=8, scalar_last=True):
    """n demos of xdot = -(x - g), rdot = -r (the known system of tests/lfd/model/test_pose.py)."""
    folder.mkdir(exist_ok=True)
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 10.0, 120)
    for i in range(n):
        x0, r0 = rng.normal(size=3), rng.uniform(-1, 1, 3)
        pos = np.exp(-t)[:, None] * x0
        q = Rotation.from_rotvec(np.exp(-t)[:, None] * r0).as_quat(scalar_first=not scalar_last)
        header = "t,x,y,z," + ("qx,qy,qz,qw" if scalar_last else "qw,qx,qy,qz")
        np.savetxt(folder / f"d{i}.csv", np.column_stack([t, pos, q]), delimiter=",", header=header, comments="")
    return folder


def test_ambiguous_header_is_one_error_line(tmp_path, capsys):
    folder = tmp_path / "demos"
    folder.mkdir()
    (folder / "a.csv").write_text("t,x,y,z,qy,qx,qz,qw\n0,0,0,0,0,0,0,1\n")
    code, _, err = run(capsys, "fit", folder, "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "neither w x y z nor x y z w", need_try=True)


def test_position_only_options_refused_for_pose_files(tmp_path, capsys):
    demos = write_pose_csvs(tmp_path / "demos", n=2)
    code, _, err = run(capsys, "fit", demos, "--goal-tol", "0.1", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "goal_tol apply to position files", "--columns", need_try=True)
    code, _, err = run(capsys, "fit", "lasa:Leaf_1", "--goal-tol-deg", "5", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--goal-tol-deg does not apply to a CDSP model (PoseCDSP takes it)",
                          need_try=True)
    assert not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("value", ["0", "180", "-1", "200"])
def test_goal_tol_deg_range_is_open_and_said(tmp_path, capsys, value):
    demos = write_pose_csvs(tmp_path / "demos", n=2)
    code, _, err = run(capsys, "fit", demos, "--goal-tol-deg", value, "--out", tmp_path / "m.json")
    assert code != 0 and "(0, 180), both ends excluded" in " ".join(err.replace("│", " ").split())
    code, out, _ = run(capsys, "fit", "--help")
    assert "0<=x<=180" not in out


@pytest.mark.slow
def test_fit_export_and_plot_pose(tmp_path, capsys):
    demos = write_pose_csvs(tmp_path / "demos", scalar_last=False)
    code, out, err = run(capsys, "fit", demos, "--units", "m", "--out", tmp_path / "pose.json")
    assert code == 0, err
    assert "fitting PoseCDSP to 8 demonstrations" in out and "certificate: passed" in out
    assert "orientation block (identity metric" in out and "preprocess: orientation noise" in out
    table = [line for line in out[out.index("demo    mean dev"):].splitlines() if line.split()[:1] and
             line.split()[0].isdigit()]
    assert len(table) == 8 and all(line.split()[-1] == "yes" for line in table)       # every demo reaches the goal
    model = load_model(tmp_path / "pose.json")
    assert model.certified_ and model.units_ == "m"
    for target, name in (("python", "pose_model.py"), ("cpp", "pose.hpp")):
        code, _, err = run(capsys, "export", tmp_path / "pose.json", "--to", target, "--out", tmp_path / name)
        assert code == 0, err
    assert "pose_model_pose" in (tmp_path / "pose.hpp").read_text()
    spec = importlib.util.spec_from_file_location("pose_model", tmp_path / "pose_model.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    x, q = np.array([0.3, -0.2, 0.5]), Rotation.from_rotvec([0.2, 0.1, -0.3]).as_quat(scalar_first=True)
    v, w = module.predict_pose(x, q)
    np.testing.assert_allclose(np.concatenate([v, w]), np.concatenate(model.predictor()(x, q)), rtol=1e-12)
    row = np.loadtxt(demos / "d0.csv", delimiter=",", skiprows=1)[10]      # on the data: the known xdot = -x
    v, w = module.predict_pose(row[1:4], row[4:])
    np.testing.assert_allclose(v, -row[1:4], atol=0.02 * np.abs(row[1:4]).max())
    code, _, err = run(capsys, "export", tmp_path / "pose.json", "--to", "python", "--max-speed", "0.1",
                       "--max-angular-speed", "0.2", "--out", tmp_path / "limited.py")
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("limited", tmp_path / "limited.py")
    limited = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(limited)
    v, w = limited.predict_pose(x, q)                       # free |v| ~ 0.6, |omega| ~ 0.4: both limits bind
    np.testing.assert_allclose(np.concatenate([v, w]), np.concatenate(
        model.predictor(max_speed=0.1, max_angular_speed=0.2)(x, q)), rtol=1e-12)
    assert np.linalg.norm(v) <= 0.1 * (1 + 1e-12) and np.linalg.norm(w) <= 0.2 * (1 + 1e-12)
    code, out, err = run(capsys, "plot", tmp_path / "pose.json", "--demos", demos, "--out", tmp_path / "p.png")
    assert code == 0 and "8 reproductions of 8 demonstrations" in out, err
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(capsys, "plot", tmp_path / "pose.json", "--out", tmp_path / "p.png")
    assert_one_error_line(code, err, "pose model is drawn with the pose demonstrations", need_try=True)
    code, _, err = run(capsys, "rollout", tmp_path / "pose.json", "--start", "0,0,0")
    assert_one_error_line(code, err, "--start has 3 numbers but the model takes 7: x,y,z,qw,qx,qy,qz",
                          need_try=True)
    example = err.split("e.g. ")[1].rstrip(".\n")                 # the hint is a valid start itself
    code, _, err = run(capsys, "rollout", tmp_path / "pose.json", "--start", example, "--duration", "1")
    assert code == 0, err
    turned = Rotation.from_rotvec([0.0, 0.0, 0.5]).as_quat(scalar_first=True)     # a rotated goal at t = 4
    goal = ",".join(f"{v:.17g}" for v in [0.2, -0.1, 0.1, *turned])
    code, out, err = run(capsys, "rollout", tmp_path / "pose.json", "--start", "0.5,0.3,-0.4,1,0,0,0",
                         "--push", "2:0.1,0,0,0,0.3,0", "--goal-change", f"4:{goal}", "--duration", "20",
                         "--max-speed", "0.2", "--max-angular-speed", "0.25", "--out", tmp_path / "run.csv")
    assert code == 0, err
    run_back = load_demos(tmp_path / "run.csv")                 # the CSV is a pose demonstration again
    assert isinstance(run_back, PoseDemonstrations)
    d = run_back[0]
    np.testing.assert_allclose(d.pos[-1], [0.2, -0.1, 0.1], atol=1e-3)
    assert angles_deg(d.quat[-1], turned)[0] < 0.1
    speed = np.linalg.norm(np.diff(d.pos, axis=0), axis=1) / np.diff(d.t)
    turn = np.deg2rad(angles_deg(d.quat[1:], d.quat[:-1])) / np.diff(d.t)
    jump = int(np.argmax(speed))                                 # the push: a jump, not a speed
    assert d.t[jump] == pytest.approx(2.0) and np.argmax(turn) == jump
    assert np.delete(speed, jump).max() <= 0.2 * 1.01 and np.delete(turn, jump).max() <= 0.25 * 1.01
    code, out, err = run(capsys, "fit", demos, "--columns", "x,y,z", "--out", tmp_path / "pos.json")
    assert code == 0 and "fitting CDSP to 8 demonstrations" in out, err     # positions selected
    assert load_model(tmp_path / "pos.json").dim_ == 3


SIM_MAIN = """#include <cmath>
#include <cstdio>
#include "pose.hpp"
// Integrates the exported field from x0, q0 (w x y z): x += v dt, q <- exp(omega dt) q; prints, per step,
// the position, the quaternion and the angular speed.
int main() {
  double x[3], q[4], v[3], w[3];
  if (std::scanf("%lf %lf %lf %lf %lf %lf %lf", x, x + 1, x + 2, q, q + 1, q + 2, q + 3) != 7) return 2;
  const double dt = 0.005;
  for (int k = 0; k < 12000; ++k) {
    if (!arm_pose::predict_pose(x, q, v, w)) return 1;
    const double th = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) * dt;
    const double s = th > 1e-12 ? std::sin(th / 2) / (th / dt) : dt / 2;
    const double d[4] = {std::cos(th / 2), s * w[0], s * w[1], s * w[2]};
    const double n[4] = {d[0] * q[0] - d[1] * q[1] - d[2] * q[2] - d[3] * q[3], d[0] * q[1] + d[1] * q[0] + d[2] * q[3] - d[3] * q[2],
                         d[0] * q[2] - d[1] * q[3] + d[2] * q[0] + d[3] * q[1], d[0] * q[3] + d[1] * q[2] - d[2] * q[1] + d[3] * q[0]};
    for (int i = 0; i < 4; ++i) q[i] = n[i];
    for (int i = 0; i < 3; ++i) x[i] += v[i] * dt;
    std::printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\\n", x[0], x[1], x[2], q[0], q[1], q[2], q[3],
                th / dt);
  }
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_newcomer_csv_to_cpp_controller_from_170_degrees(tmp_path, capsys):
    """A pose log (CSV) -> sosdyn fit -> export --to cpp (a namespace ending in _: arm_pose, never the reserved
    arm__pose) -> compiled -> run from 170 deg off at the goal position: the gripper turns home and does not
    move (no detour), smoothly; from a demo's start too."""
    logs = tmp_path / "logs"
    logs.mkdir()
    for f in sorted((DATASETS_DIR / "robottasks" / "openbox").glob("demo_0[0-5].csv")):
        shutil.copy(f, logs / f.name)
    code, out, err = run(capsys, "fit", logs, "--units", "cm", "--out", tmp_path / "pose.json")
    assert code == 0 and "certificate: passed" in out, err
    code, _, err = run(capsys, "export", tmp_path / "pose.json", "--to", "cpp", "--max-speed", "10",
                       "--max-angular-speed", "0.8", "--namespace", "arm_", "--out", tmp_path / "pose.hpp")
    assert code == 0, err
    (tmp_path / "sim.cpp").write_text(SIM_MAIN)
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(tmp_path / "sim"),
                    str(tmp_path / "sim.cpp")], check=True, capture_output=True, text=True)
    model = load_model(tmp_path / "pose.json")
    demos = load_demos(sorted(logs.glob("*.csv")))
    diag = np.linalg.norm(np.ptp(np.vstack([d.pos for d in demos]), axis=0))
    start = Rotation.from_rotvec(np.deg2rad(170) * np.array([0.0, 0.6, 0.8])) * \
        Rotation.from_quat(model.goal_quat_, scalar_first=True)
    for x0, q0 in ((model.goal_pos_, start.as_quat(scalar_first=True)), (demos[0].pos[0], demos[0].quat[0])):
        res = subprocess.run([str(tmp_path / "sim")], input=" ".join(repr(float(v)) for v in [*x0, *q0]),
                             capture_output=True, text=True, check=True)
        path = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
        angle = angles_deg(path[:, 3:7], model.goal_quat_)
        assert angle[-1] < 1.0 and np.linalg.norm(path[-1, :3] - model.goal_pos_) < 0.01 * diag
        assert np.all(np.diff(angle) <= 1e-6)                                   # never turns away
        assert path[:, 7].max() <= 0.8 * (1 + 1e-9)                             # the built-in limit
        assert np.abs(np.diff(path[:, 7])).max() < 0.05                         # smooth: no jump in |omega|
        if x0 is model.goal_pos_:
            assert np.linalg.norm(path[:, :3] - x0, axis=1).max() == 0.0        # no detour: not a micrometre


@pytest.mark.slow
def test_fit_shipped_pose_set_learns_orientations(tmp_path, capsys):
    code, out, err = run(capsys, "fit", "dataset:robottasks/openbox", "--out", tmp_path / "openbox.json")
    assert code == 0 and "fitting PoseCDSP to 9 demonstrations" in out, err
    assert "orientation block" in out and "reproduction of each demonstration" in out
    model = load_model(tmp_path / "openbox.json")
    assert model.certified_ and model.still_ == {"position": None, "orientation": None}


def test_pose_fit_progress_and_iteration_cap_name_the_block(tmp_path, capsys):
    """Each block's convex steps are shown and capped as that block's own fit: every progress line and
    every iteration-cap notice names its block (one fit's rows are never counted with the other's)."""
    demos = write_pose_csvs(tmp_path / "demos", n=3)
    code, out, err = run(capsys, "fit", demos, "--components", "2", "--max-iter", "1", "--warp", "none",
                         "--out", tmp_path / "pose.json")
    assert code == 0, err
    steps = re.findall(r"^(.*)step \d+ \(", out, re.M)
    assert {head.split(" block")[0] for head in steps} == {"position", "orientation"}
    assert all(re.fullmatch(r"(position|orientation) block, ", head) for head in steps)
    caps = re.findall(r"^iteration cap: (.*?): stopped at max_iter=1", out, re.M)
    assert len(caps) == out.count("iteration cap:") and set(caps) <= {"position block", "orientation block"}

"""``sosdyn fit`` / ``export`` / ``plot`` on pose CSVs (either quaternion order): a certified pose model
and a standalone evaluator whose (v, omega) equal the model's."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from cli_support import assert_one_error_line, run
from scipy.spatial.transform import Rotation

from sosdyn.evaluation.poses import angles_deg
from sosdyn.lfd.data.files import load_demos
from sosdyn.lfd.data.poses import PoseDemonstrations
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
    code, _, err = run(capsys, "fit", demos, "--smooth", "off", "--goal-tol", "0.1", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--goal-tol applies to position files", "--columns x,y,z", need_try=True)
    code, _, err = run(capsys, "fit", "lasa:Leaf_1", "--goal-tol-deg", "5", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--goal-tol-deg applies to pose files", need_try=True)
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
    assert "fitting PoseCDSP to 8 pose demonstrations" in out and "certificate: passed" in out
    assert "orientation certificate (identity metric" in out and "preprocess: orientation noise" in out
    table = out[out.index("reproduction of each demonstration"):].splitlines()[2:10]
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
    assert code == 0 and "8 demonstrations and rollouts" in out, err
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(capsys, "plot", tmp_path / "pose.json", "--out", tmp_path / "p.png")
    assert_one_error_line(code, err, "pose model is drawn with the pose demonstrations", need_try=True)
    code, _, err = run(capsys, "rollout", tmp_path / "pose.json", "--start", "0,0,0")
    assert_one_error_line(code, err, "--start has 3 numbers but a pose model takes 7: x,y,z,qw,qx,qy,qz",
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

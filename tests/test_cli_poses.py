"""``sosdyn fit-pose`` / ``export-pose``: pose CSVs (either quaternion order) to a certified model and a
standalone evaluator whose (v, omega) equal the model's."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from cli_support import assert_one_error_line, run
from scipy.spatial.transform import Rotation

from sosdyn.lfd.model.pose import load_pose_model


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
    (folder / "a.csv").write_text("t,x,y,z,q1,q2,q3,q4\n0,0,0,0,1,0,0,0\n")
    code, _, err = run(capsys, "fit-pose", folder, "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "q1", need_try=True)


@pytest.mark.slow
def test_fit_and_export_pose(tmp_path, capsys):
    demos = write_pose_csvs(tmp_path / "demos")
    code, out, err = run(capsys, "fit-pose", demos, "--units", "m", "--out", tmp_path / "pose.json")
    assert code == 0, err
    assert "certificate (6-D chart model): passed" in out
    code, _, err = run(capsys, "export-pose", tmp_path / "pose.json", "--out", tmp_path / "pose_model.py")
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("pose_model", tmp_path / "pose_model.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    model = load_pose_model(tmp_path / "pose.json")
    x, q = np.array([0.3, -0.2, 0.5]), Rotation.from_rotvec([0.2, 0.1, -0.3]).as_quat(scalar_first=True)
    v, w = module.predict_pose(x, q)
    np.testing.assert_allclose(np.concatenate([v, w]), np.concatenate(model.predictor()(x, q)), rtol=1e-12)
    row = np.loadtxt(demos / "d0.csv", delimiter=",", skiprows=1)[10]      # on the data: the known xdot = -x
    v, w = module.predict_pose(row[1:4], np.roll(row[4:], 1))
    np.testing.assert_allclose(v, -row[1:4], atol=0.02 * np.abs(row[1:4]).max())
    code, out, err = run(capsys, "plot-pose", tmp_path / "pose.json", "--demos", demos, "--out", tmp_path / "p.png")
    assert code == 0 and "8 demonstrations and rollouts" in out, err
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(capsys, "plot-pose", tmp_path / "pose.json", "--demos", demos, "--out", tmp_path / "p.pdf")
    assert_one_error_line(code, err, ".png or .svg", need_try=True)

"""`sosdyn export`, `sosdyn plot` and `sosdyn --version`: real models, in-process runs."""
from __future__ import annotations

import importlib.util
import shutil
import subprocess

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations

from cli_support import assert_one_error_line, run


def line_demos(starts, T=60, duration=2.0):
    """Straight motions start -> origin with a cubic time law and exact velocities."""
    t = np.linspace(0.0, duration, T)
    s, ds = 3 * (t / duration) ** 2 - 2 * (t / duration) ** 3, 6 * t / duration**2 - 6 * t**2 / duration**3
    demos = [Demonstration(t, (1 - s)[:, None] * np.asarray(a, float), -ds[:, None] * np.asarray(a, float),
                           f"demo{i}") for i, a in enumerate(starts)]
    return Demonstrations(demos, name="lines", units="mm")


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """{n: (model path, [demo CSV paths])} for 2-, 3- and 4-D line motions."""
    folder = tmp_path_factory.mktemp("models")
    rng = np.random.default_rng(3)
    out = {}
    for n in (2, 3, 4):
        demos = line_demos(rng.uniform(-10, 10, size=(3, n)))
        path = sd.CDSP(n_components=2, warp="none").fit(demos).save(folder / f"m{n}.json")
        csvs = []
        for i, d in enumerate(demos):
            csv = folder / f"d{n}_{i}.csv"
            np.savetxt(csv, np.column_stack([d.t, d.pos]), delimiter=",", comments="",
                       header=",".join(["t", *(f"x{j + 1}" for j in range(n))]))
            csvs.append(csv)
        out[n] = (path, csvs)
    return out


def test_version(capsys):
    code, stdout, _ = run(capsys, "--version")
    assert code == 0 and stdout.strip() == f"sosdyn {sd.__version__}"


def test_export_python_round_trip(capsys, saved, tmp_path):
    model_path, _ = saved[2]
    target = tmp_path / "field.py"
    code, _, err = run(capsys, "export", str(model_path), "--to", "python", "--out", str(target))
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("field_cli", target)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    model = sd.load_model(model_path)
    X = model.goal_ + model.scale_ * np.random.default_rng(0).uniform(-2, 2, size=(500, 2))
    np.testing.assert_allclose(module.predict(X), model.predict(X), rtol=1e-9, atol=1e-12 * model.scale_)


def test_export_cpp_writes_a_header(capsys, saved, tmp_path):
    target = tmp_path / "field.hpp"
    code, _, err = run(capsys, "export", str(saved[3][0]), "--to", "cpp", "--out", str(target))
    assert code == 0, err
    text = target.read_text()
    assert "#pragma once" in text and "constexpr int N = 3;" in text


def test_export_cpp_namespace_is_chosen_and_checked(capsys, saved, tmp_path):
    """--namespace names the C++ namespace (the header compiles and is called through it); a C++ keyword,
    a non-identifier, or --namespace with --to python is refused with nothing written."""
    target = tmp_path / "field.hpp"
    code, _, err = run(capsys, "export", saved[3][0], "--to", "cpp", "--namespace", "arm_ctl", "--out", target)
    assert code == 0, err
    text = target.read_text()
    assert "namespace arm_ctl {" in text and "cdsp_model" not in text
    if shutil.which("g++"):
        (tmp_path / "main.cpp").write_text('#include "field.hpp"\nint main() { double x[3] = {1, 2, 3}, v[3]; '
                                           "return arm_ctl::predict(x, v) ? 0 : 1; }\n")
        subprocess.run(["g++", "-std=c++17", "-Wall", "-Werror", "-o", str(tmp_path / "main"), str(tmp_path / "main.cpp")],
                       check=True, capture_output=True)
        assert subprocess.run([str(tmp_path / "main")]).returncode == 0
    for name, fragment in (("class", "a C++ keyword"), ("9lives", "not an ASCII C++ identifier")):
        code, _, err = run(capsys, "export", saved[3][0], "--to", "cpp", "--namespace", name, "--out", tmp_path / "x.hpp")
        assert_one_error_line(code, err, f"namespace '{name}' is {fragment}", need_try=True)
    code, _, err = run(capsys, "export", saved[3][0], "--to", "python", "--namespace", "arm_ctl", "--out", tmp_path / "x.py")
    assert_one_error_line(code, err, "--namespace names the C++ namespace", "--to cpp", need_try=True)
    assert not (tmp_path / "x.hpp").exists() and not (tmp_path / "x.py").exists()


def test_export_refuses_to_overwrite_its_input(capsys, saved):
    model_path = saved[2][0]
    before = model_path.read_bytes()
    code, _, err = run(capsys, "export", str(model_path), "--to", "python", "--out", str(model_path))
    assert code == 1 and "would destroy the input" in err
    assert model_path.read_bytes() == before


def test_export_unknown_target_is_a_usage_error(capsys, saved, tmp_path):
    code, _, err = run(capsys, "export", str(saved[2][0]), "--to", "rust", "--out", str(tmp_path / "x.rs"))
    assert code == 2 and "rust" in err


def test_export_angular_speed_is_for_pose_models(capsys, saved, tmp_path):
    code, _, err = run(capsys, "export", str(saved[2][0]), "--to", "python", "--max-angular-speed", "1",
                       "--out", str(tmp_path / "x.py"))
    assert code == 1 and "--max-angular-speed does not apply to a CDSP model (PoseCDSP takes it)" in err and "Try:" in err
    assert not (tmp_path / "x.py").exists()


@pytest.mark.parametrize("n", [2, 3, 4])
def test_plot_writes_a_png(capsys, saved, tmp_path, n):
    model_path, csvs = saved[n]
    target = tmp_path / f"m{n}.png"
    demo_args = [a for c in csvs for a in ("--demos", str(c))]
    code, _, err = run(capsys, "plot", str(model_path), *demo_args, "--out", str(target))
    assert code == 0, err
    data = target.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_plot_svg_without_demos(capsys, saved, tmp_path):
    target = tmp_path / "m.svg"
    code, _, err = run(capsys, "plot", str(saved[2][0]), "--out", str(target), "--duration", "3")
    assert code == 0, err
    assert target.read_text().lstrip().startswith("<?xml") and "<svg" in target.read_text()


def test_plot_checks_out_before_work(capsys, saved, tmp_path):
    model_path, csvs = saved[2]
    code, _, err = run(capsys, "plot", str(model_path), "--out", str(tmp_path / "fig.pdf"))
    assert code == 1 and ".png or .svg" in err
    (tmp_path / "dir.png").mkdir()
    code, _, err = run(capsys, "plot", str(model_path), "--demos", str(csvs[0]), "--out", str(tmp_path / "dir.png"))
    assert code == 1 and "is a folder" in err
    link = tmp_path / "demo.png"
    link.symlink_to(csvs[0])
    code, _, err = run(capsys, "plot", str(model_path), "--demos", str(csvs[0]), "--out", str(link))
    assert code == 1 and "would destroy the input" in err
    code, _, err = run(capsys, "plot", str(model_path), "--demos", str(saved[3][1][0]),
                       "--out", str(tmp_path / "x.png"))
    assert code == 1 and "3-D but the model is 2-D" in err
    assert not (tmp_path / "x.png").exists()


def test_export_max_speed_python_and_cpp(capsys, saved, tmp_path):
    """--max-speed is written into both exports: |xdot| <= v, directions kept, goal movable."""
    model_path, _ = saved[3]
    model = sd.load_model(model_path)
    X = model.goal_ + model.scale_ * np.random.default_rng(1).uniform(-2, 2, size=(300, 3))
    v = 0.5 * float(np.median(np.linalg.norm(model.predict(X), axis=1)))
    code, _, err = run(capsys, "export", model_path, "--to", "python", "--max-speed", v, "--out", tmp_path / "f.py")
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("field_speed", tmp_path / "f.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    goal = model.goal_ + 1.0
    step = model.predictor(max_speed=v)
    np.testing.assert_allclose(module.predict(X, goal=goal), [step(x, goal=goal) for x in X], rtol=1e-12)
    assert np.linalg.norm(module.predict(X), axis=1).max() <= v * (1 + 1e-12)
    code, _, err = run(capsys, "export", model_path, "--to", "cpp", "--max-speed", v, "--out", tmp_path / "f.hpp")
    assert code == 0, err
    text = (tmp_path / "f.hpp").read_text()
    assert f"constexpr double max_speed = {v!r};" in text and "const double* goal = nullptr" in text
    code, _, err = run(capsys, "export", model_path, "--to", "cpp", "--max-speed", 0, "--out", tmp_path / "g.hpp")
    assert code == 2 and "--max-speed" in err


def test_rollout_with_pushes_goal_changes_and_a_speed_limit(capsys, saved, tmp_path):
    model_path, _ = saved[2]
    model = sd.load_model(model_path)
    start = model.goal_ + model.scale_ * np.array([1.0, 0.5])
    new_goal = model.goal_ + [3.0, -2.0]
    traj = tmp_path / "traj.csv"
    code, out, err = run(capsys, "rollout", model_path, "--start", ",".join(repr(float(v)) for v in start),
                         "--push", "1:2,0", "--goal-change", f"2:{float(new_goal[0])!r},{float(new_goal[1])!r}",
                         "--duration", 30, "--max-speed", 4.0, "--dt", 0.01, "--out", traj)
    assert code == 0, err
    data = np.loadtxt(traj, delimiter=",", skiprows=1)
    want = model.rollout(start, 30.0, dt=0.01, perturbations=[(1.0, [2, 0])], goal_changes=[(2.0, new_goal)],
                         max_speed=4.0)
    np.testing.assert_allclose(data[:, 1:], want.pos, atol=1e-9)
    np.testing.assert_allclose(data[-1, 1:], new_goal, atol=0.05)          # reaches the moved goal
    steps = np.linalg.norm(np.diff(data[:, 1:], axis=0), axis=1)
    jump = int(np.argmax(steps))
    assert data[jump + 1, 0] == pytest.approx(1.0) and steps[jump] > 1.5      # the push at t = 1
    assert np.delete(steps, jump).max() / 0.01 <= 4.0 * 1.01                  # --max-speed 4
    assert "goal (" in out


@pytest.mark.parametrize("argv, fragments", [
    (["--start", "1,2,3"], ["--start has 3 numbers but the model takes 2: x1,x2", "Try: 2 comma-separated"]),
    (["--start", "1,2", "--push", "1:5"], ["--push has 1 numbers but the model takes 2"]),
    (["--start", "1,2", "--push", "x:5,0"], ["--push expects TIME:VECTOR like 2:5,0"]),
    (["--start", "1,2", "--goal-change", "20:1,1"], ["--goal-change time 20 is outside [0, --duration 10]"]),
])
def test_rollout_bad_options_are_named(capsys, saved, argv, fragments):
    code, _, err = run(capsys, "rollout", saved[2][0], *argv)
    assert_one_error_line(code, err, *fragments, need_try=True)
    assert "--debug" not in err


def test_plot_demos_takes_several_files_a_folder_or_a_pattern(capsys, saved, tmp_path):
    model_path, csvs = saved[3]
    for i, words in enumerate((["--demos", *csvs], ["--demos", csvs[0].parent / "d3_*.csv"],
                               ["--demos", csvs[0], "--demos", csvs[1], csvs[2]])):
        target = tmp_path / f"p{i}.png"
        code, out, err = run(capsys, "plot", model_path, *words, "--out", target)
        assert code == 0, err
        assert "3 reproductions" in out and target.read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(capsys, "plot", model_path, csvs[0], "--out", tmp_path / "x.png")
    assert_one_error_line(code, err, "unexpected arguments", "Try: --demos")


def test_3d_plot_draws_wall_projections_and_lists_only_what_it_shows(saved):
    from sosdyn.report.figures import trajectories_3d

    model = sd.load_model(saved[3][0])
    run_ = model.rollout(model.goal_ + model.scale_, 5.0).pos
    demo = run_ + 0.1
    fig = trajectories_3d([demo], [run_], model.goal_)
    ax = fig.axes[0]
    lines = ax.get_lines()
    assert len(lines) == 2 * 4 + 4                 # each path and its 3 projections; the goal and its 3
    floors = [ln for ln in lines if np.allclose(ln.get_data_3d()[2], ax.get_zlim()[0])]
    assert len(floors) == 3                        # demo, reproduction, goal on the x1-x2 floor
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["demonstrations", "reproductions", "goal", "projections on the walls"]
    labels = [t.get_text() for t in trajectories_3d([], [run_], model.goal_).legends[0].get_texts()]
    assert "demonstrations" not in labels


def test_2d_plot_without_demos_has_no_demonstrations_entry(saved):
    from sosdyn.report.figures import streamlines

    model = sd.load_model(saved[2][0])
    fig = streamlines(None, model.predict, [], [model.rollout(model.goal_ + model.scale_, 3.0).pos], model.goal_)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == [
        "streamlines of the model", "reproductions", "goal"]

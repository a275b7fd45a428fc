"""The ``sosdyn`` command line: error lines, option plumbing, and a real fit/rollout round trip."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.cli import main
from sosdyn.errors import DemonstrationError

from cli_support import assert_one_error_line, run


# ------------------------------------------------------------------------ error paths

def test_fit_missing_demo_file(capsys, tmp_path):
    code, _, err = run(capsys, "fit", str(tmp_path / "nope.csv"), "--out", str(tmp_path / "m.json"))
    assert_one_error_line(code, err, "demonstration file not found", "nope.csv")


def test_rollout_bad_start_and_missing_model(capsys, tmp_path):
    code, _, err = run(capsys, "rollout", str(tmp_path / "m.json"), "--from", "1,abc")
    assert_one_error_line(code, err, "--start expects comma-separated numbers", "'1,abc'")
    code, _, err = run(capsys, "rollout", str(tmp_path / "m.json"), "--from", "1,2")
    assert_one_error_line(code, err, "model file not found")


def test_report_missing_results(capsys, tmp_path):
    code, _, err = run(capsys, "report", "--results", str(tmp_path / "results.json"), "--out", str(tmp_path))
    assert_one_error_line(code, err, "results file not found")


def test_sosdyn_error_from_the_library_is_one_line(capsys, monkeypatch):
    def broken(name):
        raise DemonstrationError(f"demos of {name} end at different goals; check the data.")

    monkeypatch.setattr(sd, "load_lasa", broken, raising=False)
    code, _, err = run(capsys, "fit", "lasa:Leaf_1")
    assert_one_error_line(code, err, "demos of Leaf_1 end at different goals")


def test_debug_shows_the_exception(capsys, tmp_path):
    with pytest.raises(FileNotFoundError):
        main(["--debug", "fit", str(tmp_path / "nope.csv")])


def test_usage_errors_are_clicks(capsys):
    code, _, err = run(capsys, "rollout")
    assert code == 2 and "Missing argument" in err


def test_real_process_prints_no_traceback(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sosdyn.cli", "fit", str(tmp_path / "x.csv")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [
        f"error: demonstration file not found: {tmp_path / 'x.csv'}. Try: check the path."]


# ---------------------------------------------------------------- experiment command

_REGISTRY = """
import importlib

EXPERIMENTS = {"hello-world": "hello_world", "needs-missing": "needs_missing"}


def run_experiment(name, argv=()):
    module = importlib.import_module(f"{__name__}.{EXPERIMENTS[name.replace('_', '-')]}")
    return module.main(list(argv)) or 0
"""


@pytest.fixture
def repo(tmp_path, monkeypatch):
    """A throw-away repository with a problems/ package, away from the working directory."""
    pkg = tmp_path / "repo" / "problems"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(_REGISTRY)
    (pkg / "hello_world.py").write_text(
        "from pathlib import Path\n\ndef main(argv):\n    Path('ran.txt').write_text(' '.join(argv) or 'yes')\n")
    (pkg / "needs_missing.py").write_text("import no_such_module_xyz\n\ndef main(argv):\n    pass\n")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    monkeypatch.setattr(sys, "path", list(sys.path))
    for name in _problems_modules():
        monkeypatch.delitem(sys.modules, name)
    yield tmp_path / "repo"
    for name in _problems_modules():        # the throw-away package must not outlive the test
        sys.modules.pop(name)               # (monkeypatch then restores the real one, if any)


def _problems_modules() -> list:
    return [m for m in sys.modules if m == "problems" or m.startswith("problems.")]


def test_experiment_runs_main_from_any_folder(capsys, repo):
    code, _, err = run(capsys, "experiment", "hello-world", "--repo", str(repo), "--quick", "--shapes", "A")
    assert code == 0, err
    assert (repo.parent / "elsewhere" / "ran.txt").read_text() == "--quick --shapes A"


def test_experiment_without_problems_folder_is_a_typed_error(capsys, tmp_path):
    code, _, err = run(capsys, "experiment", "fig1", "--repo", str(tmp_path))
    assert_one_error_line(code, err, "no experiments found", "has no problems/ folder", "Try: --repo")


def test_experiment_default_is_the_source_tree_of_sosdyn():
    from sosdyn import cli
    assert cli.SOURCE_TREE == Path(sd.__file__).resolve().parents[1]
    assert cli.experiments_package().EXPERIMENTS["fig1"] == "fig1"     # this checkout's problems/


def test_experiment_unknown_lists_the_known_ones(capsys):
    code, _, err = run(capsys, "experiment", "fig99")
    assert_one_error_line(code, err, "no experiment 'fig99'", "run, report, fig1", "bench-sos")


def test_experiment_missing_dependency_is_not_hidden(repo):
    with pytest.raises(ModuleNotFoundError, match="no_such_module_xyz"):
        main(["experiment", "needs_missing", "--repo", str(repo)])


# ------------------------------------------------- option plumbing with stand-in models

def test_fit_passes_only_given_options(capsys, monkeypatch, tmp_path):
    made = {}

    class FakeCDSP(sd.CDSP):
        def __init__(self, **kwargs):
            made["kwargs"] = kwargs
            super().__init__(**kwargs)

        history_ = [{"step": "dynamics", "cost": 1.0}]
        certified_ = True

        def fit(self, demos):
            made["demos"] = demos
            return self

        def save(self, path, key=None):
            path.write_text("{}")

        def score(self, demos):
            return []

        def summary(self):
            return ["stand-in"]

    demo_file = tmp_path / "d1.csv"
    demo_file.write_text("t,x1,x2\n" + "".join(f"{k},{1 - k / 11},{1 - k / 11}\n" for k in range(12)))
    monkeypatch.setattr("sosdyn.cli.fit.family_for", lambda data, order=1: FakeCDSP)
    code, out, err = run(capsys, "fit", str(demo_file), "--out", str(tmp_path / "m.json"),
                         "--components", "3", "--solver-method", "ica", "--seed", "7", "--max-iter", "9",
                         "--gating", "tempered", "--speed-floor", "2.5")
    assert code == 0, err
    assert made["kwargs"] == {"n_components": 3, "solver_method": "ica", "random_state": 7, "max_iter": 9,
                              "gating": "tempered", "speed_floor": 2.5}
    assert [d.source for d in made["demos"]] == [demo_file.name]
    assert (tmp_path / "m.json").exists() and "saved" in out


def test_fit_rejects_unknown_method(capsys, tmp_path):
    code, _, err = run(capsys, "fit", "x.csv", "--method", "newton")
    assert code == 2 and "newton" in err


@pytest.mark.parametrize("value", ["fast", "0", "-1", "nan"])
def test_fit_rejects_a_bad_speed_floor(capsys, value):
    code, _, err = run(capsys, "fit", "x.csv", "--speed-floor", value)
    assert code == 2 and "--speed-floor" in err


def test_rollout_writes_csv(capsys, monkeypatch, tmp_path):
    calls = {}

    class FakeModel:
        def layout(self):
            return sd.lfd.model.Layout(("x1", "x2"), (("x1", "x2"),), ("x1", "x2"), ("x1", "x2"))

        def rollout(self, x0, duration, dt=0.01, perturbations=(), goal_changes=(), max_speed=None):
            calls.update(x0=x0, duration=duration, dt=dt, perturbations=perturbations, goal_changes=goal_changes,
                         max_speed=max_speed)
            t = np.arange(0.0, duration + dt / 2, dt)
            return SimpleNamespace(t=t, states=np.outer(np.exp(-t), x0), goal_history=np.zeros((len(t), 2)))

    model_file = tmp_path / "m.json"
    model_file.write_text("{}")
    monkeypatch.setattr(sd, "load_model", lambda path: FakeModel(), raising=False)
    code, out, err = run(capsys, "--quiet", "rollout", str(model_file), "--from", "10,-5",
                         "--duration", "2", "--dt", "0.5", "--out", str(tmp_path / "traj.csv"))
    assert code == 0, err
    assert calls["dt"] == 0.5 and calls["duration"] == 2.0
    np.testing.assert_array_equal(calls["x0"], [10.0, -5.0])
    lines = (tmp_path / "traj.csv").read_text().splitlines()
    assert lines[0] == "t,x1,x2" and len(lines) == 1 + 5
    assert lines[1] == "0,10,-5" and lines[2] == "0.5,6.0653066,-3.0326533"    # readable, not %.18e
    np.testing.assert_allclose(np.loadtxt(tmp_path / "traj.csv", delimiter=",", skiprows=1)[:, 1],
                               10 * np.exp(-np.arange(5) * 0.5), rtol=1e-8)
    assert "wrote" not in out and out.startswith("t = 2 s: x = (1.353, -0.6767), goal (0, 0)")
    assert calls["perturbations"] == [] and calls["goal_changes"] == [] and calls["max_speed"] is None


def test_lasa_list_prints_one_name_per_line(capsys, monkeypatch):
    monkeypatch.setattr(sd, "lasa_names", lambda: ["Angle", "BendedLine", "Leaf_1"], raising=False)
    code, out, _ = run(capsys, "lasa", "list")
    assert code == 0 and out.splitlines() == ["Angle", "BendedLine", "Leaf_1"]


def test_report_command_builds_both_files(capsys, tmp_path):
    (tmp_path / "results.json").write_text(json.dumps({"meta": {"seed": 0}, "findings": [
        {"title": "metric collapse", "text": "constant", "numbers": {"shapes": 4}}]}))
    code, out, err = run(capsys, "report", "--results", str(tmp_path / "results.json"),
                         "--out", str(tmp_path / "out"))
    assert code == 0, err
    assert (tmp_path / "out" / "index.html").is_file() and (tmp_path / "out" / "report.pdf").is_file()
    assert "report.pdf" in out


# -------------------------------------------------------- against the real learner API

@pytest.mark.skipif(not hasattr(sd, "lasa_names"), reason="sd.lasa_names is not implemented yet")
def test_lasa_list_real(capsys):
    code, out, err = run(capsys, "lasa", "list")
    assert code == 0, err
    names = out.splitlines()
    assert len(names) == 30 and "Leaf_1" in names and "BendedLine" in names


def _write_spiral_demos(folder, n=3, T=120):
    """Curved 2-D demonstrations converging to the origin, as CSV files with t,x1,x2."""
    paths = []
    t = np.linspace(0.0, 3.0, T)
    for i in range(n):
        ang = 0.4 * i + 1.2 * t
        r = (40.0 + 4.0 * i) * np.exp(-1.5 * t)
        xy = np.column_stack([r * np.cos(ang), r * np.sin(ang)])
        xy -= xy[-1]
        path = folder / f"demo{i}.csv"
        np.savetxt(path, np.column_stack([t, xy]), delimiter=",", header="t,x1,x2", comments="")
        paths.append(path)
    return paths


@pytest.mark.skipif(not hasattr(sd, "CDSP"), reason="sd.CDSP is not implemented yet (lead's learner API)")
def test_fit_save_rollout_round_trip(capsys, tmp_path):
    demos = _write_spiral_demos(tmp_path)
    model = tmp_path / "model.json"
    code, _, err = run(capsys, "fit", *map(str, demos), "--out", str(model), "--components", "2", "--seed", "0")
    assert code == 0, err
    assert model.is_file() and json.loads(model.read_text())
    start = np.loadtxt(demos[0], delimiter=",", skiprows=1)[0, 1:]
    traj = tmp_path / "traj.csv"
    code, out, err = run(capsys, "rollout", str(model), "--from", f"{start[0]},{start[1]}",
                         "--duration", "15", "--out", str(traj))
    assert code == 0, err
    data = np.loadtxt(traj, delimiter=",", skiprows=1)
    assert data.shape[1] == 3 and np.all(np.isfinite(data))
    np.testing.assert_allclose(data[0, 1:], start, atol=1e-9)
    assert np.all(np.diff(data[:, 0]) > 0)
    # a certified model converges: the end point is near the common goal (the origin)
    assert np.linalg.norm(data[-1, 1:]) < 0.05 * np.linalg.norm(start)

"""Every command on every model family through the CLI (issue 34.1): ``sosdyn fit --order 2`` and the
commands on a second-order file (plot, rollout, export --to python|cpp), which raised AttributeError /
TypeError before; the newcomer's path from a crossing mouse log to a compiled C++ second-order
controller; column names and units remembered by the model file."""
from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess

import numpy as np
import pytest
from cli_support import assert_one_error_line, run

import sosdyn as sd
from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.report.figures import model_figure


def crossing_log(folder):
    """The shipped crossing "e" strokes as a user has them: a folder of time_ms,x,y mouse logs."""
    shutil.copytree(DATASETS_DIR / "crossing" / "e", folder)
    return folder


def import_module(path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


MAIN = """#include "controller.hpp"
#include <cstdio>
int main(int argc, char** argv) {
  double x[2], v[2], a[2];
  if (argc != 5) return 2;
  for (int i = 0; i < 2; ++i)
    if (std::sscanf(argv[1 + i], "%lf", &x[i]) != 1 || std::sscanf(argv[3 + i], "%lf", &v[i]) != 1) return 2;
  if (!second_order_model::acceleration(x, v, a)) return 1;
  std::printf("%.17g %.17g\\n", a[0], a[1]);
}
"""


@pytest.fixture(scope="module")
def second_order_file(tmp_path_factory):
    """``sosdyn fit LOG --order 2`` on the crossing log (the default, tracking field)."""
    folder = tmp_path_factory.mktemp("o2")
    logs = crossing_log(folder / "e")
    model = folder / "o2.json"
    code, out, err = _run_uncaptured("fit", logs, "--order", "2", "--out", model)
    assert code == 0, err
    return model, logs, out


def _run_uncaptured(*argv):
    """run() without capsys, for module fixtures: (code, stdout, stderr)."""
    import contextlib
    import io

    from sosdyn.cli import main
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in argv])
            code = 0
        except SystemExit as exc:
            code = exc.code or 0
    return code, out.getvalue(), err.getvalue()


def test_fit_order_2_fits_a_certified_second_order_model(second_order_file):
    model, _, out = second_order_file
    loaded = sd.load_model(model)
    assert isinstance(loaded, sd.SecondOrderCDSP) and loaded.certified_
    assert "fitting SecondOrderCDSP to 7 demonstrations of e" in out and "certificate: passed" in out
    assert "reproduction of each demonstration from its start" in out        # the score table
    assert "crossing(s) of the demonstrations" not in out                         # it can follow them
    assert loaded.units_ == "" and loaded.columns_ == ("x", "y")


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_newcomer_crossing_log_to_compiled_second_order_controller(second_order_file, capsys, tmp_path):
    """fit --order 2 -> export --to cpp -> g++ -> one state: predict's acceleration to 1e-9."""
    model, _, _ = second_order_file
    code, out, err = run(capsys, "export", model, "--to", "cpp", "--out", tmp_path / "controller.hpp")
    assert code == 0 and "wrote" in out, err
    (tmp_path / "main.cpp").write_text(MAIN)
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(tmp_path / "ctl"),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    x, v = np.array([-120.0, 40.0]), np.array([150.0, -80.0])
    res = subprocess.run([str(tmp_path / "ctl"), *(repr(float(a)) for a in [*x, *v])], capture_output=True, text=True,
                         check=True)
    got = np.array([float(a) for a in res.stdout.split()])
    want = sd.load_model(model).predict(x, v)[0]
    assert np.abs(got - want).max() <= 1e-9 * np.abs(want).max()


def test_plot_rollout_export_work_on_a_second_order_file(second_order_file, capsys, tmp_path):
    """plot (AttributeError 'units_' before), rollout (TypeError 'max_speed'), export (AttributeError
    'field_exps_'): each works, with the second-order options."""
    model, logs, _ = second_order_file
    fitted = sd.load_model(model)
    for demos in ([], ["--demos", logs]):
        code, out, err = run(capsys, "plot", model, *demos, "--out", tmp_path / "p.png")
        assert code == 0 and "2-D SecondOrderCDSP model" in out, err
        assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"
    code, out, err = run(capsys, "rollout", model, "--start", "-150,40", "--start-velocity", "100,-50",
                         "--push", "1:5,0,0,20", "--goal-change", "2:10,-10", "--max-speed", "80", "--duration", "20",
                         "--out", tmp_path / "run.csv")
    assert code == 0, err
    lines = (tmp_path / "run.csv").read_text().splitlines()
    assert lines[0] == "t,x,y"
    rows = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1)
    speed = np.linalg.norm(np.diff(rows[:, 1:], axis=0), axis=1) / np.diff(rows[:, 0])
    jump = np.argmin(np.abs(rows[1:, 0] - 1.0))
    assert np.delete(speed, [jump - 1, jump, jump + 1]).max() <= 80 * 1.01
    assert np.linalg.norm(rows[-1, 1:] - [10, -10]) < 1.0 and "goal (10, -10)" in out
    code, out, err = run(capsys, "export", model, "--to", "python", "--out", tmp_path / "acc.py")
    assert code == 0, err
    module = import_module(tmp_path / "acc.py")
    X, V = np.array([[-100.0, 30.0], [20.0, 5.0]]), np.array([[50.0, 0.0], [-10.0, 40.0]])
    np.testing.assert_allclose(module.acceleration(X, V), fitted.predict(X, V), rtol=1e-12)
    assert module.COLUMNS == ("x", "y")


def test_options_of_other_families_are_refused_by_name(second_order_file, capsys, tmp_path):
    model, logs, _ = second_order_file
    code, _, err = run(capsys, "rollout", model, "--start", "1,2", "--max-angular-speed", "1")
    assert_one_error_line(code, err, "--max-angular-speed does not apply to a SecondOrderCDSP model (PoseCDSP",
                          need_try=True)
    code, _, err = run(capsys, "export", model, "--to", "cpp", "--max-speed", "3", "--out", tmp_path / "x.hpp")
    assert_one_error_line(code, err, "time change", "sosdyn rollout --max-speed", need_try=True)
    code, _, err = run(capsys, "rollout", model, "--start", "1,2", "--start-velocity", "1,2,3")
    assert_one_error_line(code, err, "v0 must have shape (2,)", need_try=True)
    code, _, err = run(capsys, "fit", logs, "--order", "2", "--warp", "none", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--warp does not apply to a SecondOrderCDSP model (CDSP and PoseCDSP take it)",
                          need_try=True)
    code, _, err = run(capsys, "fit", logs, "--order", "2", "--preset", "ica", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "SecondOrderCDSP has none", need_try=True)
    code, _, err = run(capsys, "fit", logs, "--order", "2", "--components", "3", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--components applies to a SecondOrderCDSP model with --field mixture only, not "
                          "with the default --field tracking. Try: add --field mixture, or drop --components.")
    code, _, err = run(capsys, "fit", logs, "--order", "2", "--field", "tracking", "--max-iter", "3",
                       "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--max-iter applies to a SecondOrderCDSP model with --field mixture only, not "
                          "with --field tracking.", "Try: add --field mixture")
    code, _, err = run(capsys, "fit", logs, "--solver-method", "energy", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "solver_method must be one of ('alternating', 'ica'), got 'energy'", need_try=True)
    code, _, err = run(capsys, "fit", logs, "--field", "mixture", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "--field does not apply to a CDSP model (SecondOrderCDSP takes it)",
                          need_try=True)
    assert not (tmp_path / "m.json").exists()


def test_fit_order_2_field_mixture(capsys, tmp_path):
    """``--field mixture`` gives the mixture of linear fields, with its options: the components, the
    iteration cap (its notice read from the second-order rows) and the solver method (second order's own
    "energy" included)."""
    logs = crossing_log(tmp_path / "e")
    code, out, err = run(capsys, "fit", logs, "--order", "2", "--field", "mixture", "--components", "3",
                         "--max-iter", "1", "--solver-method", "energy", "--out", tmp_path / "m.json")
    assert code == 0, err
    loaded = sd.load_model(tmp_path / "m.json")
    assert loaded.field == "mixture" and loaded.C_.shape[0] == 3 and loaded.certified_
    assert loaded.solver_method == "energy" and loaded.max_iter == 1
    steps = re.findall(r"^step (\d+) \((\w+)\): cost (\S+)", out, re.M)       # the progress lines
    assert [s[:2] for s in steps] == [("1", "start"), ("2", "energy")]
    old, new = float(steps[0][2]), float(steps[1][2])
    cap = re.search(r"iteration cap: the fit: stopped at max_iter=1 with relative change (\S+) > tol=0.0001 "
                    r"\(more iterations: --max-iter\)", out)
    assert cap and float(cap[1]) == pytest.approx((old - new) / new, rel=1e-2)      # printed to 3 and 6 digits


def test_first_order_fit_of_crossings_points_to_order_2(capsys, tmp_path):
    logs = crossing_log(tmp_path / "e")
    code, out, err = run(capsys, "fit", logs, "--components", "2", "--warp", "none", "--max-iter", "2",
                         "--out", tmp_path / "m.json")
    assert code == 0, err
    assert re.search(r"\d+ crossings? involving \d+ demonstrations?", out) and "sosdyn fit --order 2" in out
    code, _, err = run(capsys, "rollout", tmp_path / "m.json", "--start", "1,2", "--start-velocity", "0,0")
    assert_one_error_line(code, err, "--start-velocity does not apply to a CDSP model (SecondOrderCDSP takes it)",
                          need_try=True)


def test_columns_and_units_live_in_the_model_file(capsys, tmp_path):
    """Fitted with --columns and --units, the file remembers both: plot needs no --columns and names
    its axes, rollout writes the names as its CSV header, the exports carry them."""
    folder = tmp_path / "logs"
    folder.mkdir()
    t = np.linspace(0.0, 2.0, 60)
    for i, start in enumerate(([8.0, 2.0], [-6.0, 7.0])):
        pos = np.exp(-2 * t)[:, None] * start
        np.savetxt(folder / f"d{i}.csv", np.column_stack([t, pos, np.ones_like(t)]), delimiter=",",
                   header="t,shoulder,elbow,gripper", comments="")
    model = tmp_path / "arm.json"
    code, _, err = run(capsys, "fit", folder, "--columns", "shoulder,elbow", "--units", "rad", "--components", "1",
                       "--warp", "none", "--out", model)
    assert code == 0, err
    fitted = sd.load_model(model)
    assert fitted.columns_ == ("shoulder", "elbow") and fitted.units_ == "rad"
    code, out, err = run(capsys, "plot", model, "--demos", folder, "--out", tmp_path / "arm.png")
    assert code == 0 and "2 demonstrations" in out, err
    data = sd.load_demos(sorted(folder.glob("*.csv")), columns=fitted.columns_)
    axes = model_figure(fitted.reproductions(data), "arm").axes[0]
    assert (axes.get_xlabel(), axes.get_ylabel()) == ("shoulder (rad)", "elbow (rad)")
    code, _, err = run(capsys, "rollout", model, "--start", "3,3", "--out", tmp_path / "run.csv")
    assert code == 0, err
    assert (tmp_path / "run.csv").read_text().splitlines()[0] == "t,shoulder,elbow"
    code, _, err = run(capsys, "export", model, "--to", "cpp", "--out", tmp_path / "arm.hpp")
    assert code == 0 and '{"shoulder", "elbow"}' in (tmp_path / "arm.hpp").read_text(), err

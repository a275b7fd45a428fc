"""``sosdyn fit`` as a newcomer uses it: folders and patterns of CSVs, x,y / t,x,y,z headers,
--dt, --units, --goal-tol, visible progress, and the whole CSV -> fit -> plot -> export path."""
from __future__ import annotations

import importlib.util
import json
import re
import typing

import numpy as np
import pytest
from scipy.linalg import expm
from cli_support import assert_one_error_line, run

import sosdyn as sd
from sosdyn.cli.fit import progress_line
from sosdyn.lfd.fit.learner import capped
from sosdyn.lfd.fit.warp import AUTO_WARPS

DT = 0.02


def spiral(start, T=120, rate=(0.9, 2.0)):
    """x(t) = exp(-a t) R(w t) start: a spiral into the origin, sampled every DT s."""
    t = np.arange(T) * DT * 3
    a, w = rate
    c, s = np.cos(w * t), np.sin(w * t)
    x0, y0 = start
    return t, np.exp(-a * t)[:, None] * np.column_stack([c * x0 - s * y0, s * x0 + c * y0])


def write_xy(folder, starts, header="x,y", T=120):
    """One CSV per start: positions only (no time column), header ``header``."""
    folder.mkdir(exist_ok=True)
    paths = []
    for i, s in enumerate(starts):
        _, pos = spiral(s, T)
        path = folder / f"demo_{i}.csv"
        np.savetxt(path, pos, delimiter=",", header=header, comments="")
        paths.append(path)
    return paths


class Captured(sd.CDSP):
    """A stand-in first-order family that records its parameters and the data it is given (no
    optimisation); the CLI is given it for the family the data call for."""

    made: typing.ClassVar[dict] = {}
    history_: typing.ClassVar[list] = [{"step": "dynamics", "cost": 1.0}]
    certified_ = True

    def __init__(self, **kwargs):
        Captured.made.clear()
        Captured.made["kwargs"] = kwargs
        super().__init__(**{k: v for k, v in kwargs.items() if k != "preset"})

    @classmethod
    def preset(cls, name, **kwargs):
        return cls(preset=name, **kwargs)

    def fit(self, demos):
        Captured.made["demos"] = demos
        return self

    def save(self, path, key=None):
        path.write_text("{}")

    def score(self, demos):
        return []

    def summary(self):
        return ["stand-in"]


@pytest.fixture(scope="module")
def linear_demos_2d():
    """xdot = A x with A = [[-1, 4], [0, -1]]: contracting in a learned metric only (not in M = I),
    so the ICA iterations keep lowering the cost."""
    A = np.array([[-1.0, 4.0], [0.0, -1.0]])
    t = np.linspace(0.0, 6.0, 120)
    demos = []
    for s in ((-8, 3), (6, 4), (-5, -6)):
        pos = np.array([expm(A * tk) @ np.asarray(s, float) for tk in t])
        demos.append(sd.Demonstration(t, pos, pos @ A.T, f"{s}"))
    return sd.Demonstrations(demos, "linear")


@pytest.fixture
def captured(monkeypatch):
    monkeypatch.setattr("sosdyn.cli.fit.family_for", lambda data, order=1: Captured)
    Captured.made.clear()
    return Captured.made


def test_newcomer_csv_folder_fit_plot_export(capsys, tmp_path):
    """The README's path: CSVs without a time column in a folder -> fit -> plot -> export."""
    starts = [(8, 2), (-6, 7), (5, -8)]
    folder = tmp_path / "demos"
    write_xy(folder, starts)
    model = tmp_path / "model.json"
    code, out, err = run(capsys, "fit", folder, "--dt", DT * 3, "--units", "m", "--components", "2",
                         "--out", model)
    assert code == 0, err
    steps = re.findall(r"^warp (.+?), step (\d+) \((.+)\): cost ([-\d.e+]+) \(([\d.]+) s; ([\d.]+) s since start\)$",
                       out, flags=re.MULTILINE)
    content = json.loads(model.read_text())
    history = content["state"]["history_"]
    per_warp = {w: [int(s[1]) for s in steps if s[0] == w] for w in ("none", *AUTO_WARPS)}
    # (a candidate whose bumps equal an earlier one's reuses that fit and prints no steps of its own)
    assert {"none", *list(AUTO_WARPS)[:1]} <= {s[0] for s in steps} <= set(per_warp)
    assert len(steps) == sum(map(len, per_warp.values()))
    # one plain line per convex step of every candidate of warp="auto"; the kept one's are the file's history
    assert [r["iteration"] + 1 for r in history] in per_warp.values() and len(history) >= 2
    assert "3 demonstrations of demos" in out and "certificate: passed" in out
    assert content["state"]["units_"] == "m" and content["state"]["dt_"] == pytest.approx(DT * 3)
    code, _, err = run(capsys, "plot", model, "--demos", folder, "--dt", DT * 3, "--out", tmp_path / "fig.png")
    assert code == 0, err
    assert (tmp_path / "fig.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = run(capsys, "export", model, "--to", "python", "--out", tmp_path / "field.py")
    assert code == 0, err
    spec = importlib.util.spec_from_file_location("field_newcomer", tmp_path / "field.py")
    field = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(field)
    fitted = sd.load_model(model)
    X = np.array([s for s in starts], dtype=float)
    np.testing.assert_allclose(field.predict(X), fitted.predict(X), rtol=1e-9)
    assert field.UNITS == "m"
    # the reproductions reach the goal: the demonstrations end within 1e-3 of the origin
    end = fitted.rollout(np.array(starts[0], float), 30.0).pos[-1]
    assert np.linalg.norm(end - fitted.goal_) < 0.02 * np.linalg.norm(starts[0])


def test_pattern_and_3d_t_x_y_z_header(capsys, tmp_path, captured):
    t = np.linspace(0, 2, 40)
    for i, start in enumerate(([3, 1, 2], [-2, 4, 1])):
        pos = np.outer(1 - t / 2, start)
        np.savetxt(tmp_path / f"run{i}.csv", np.column_stack([t, pos]), delimiter=",", header="t,x,y,z",
                   comments="")
    (tmp_path / "notes.txt").write_text("not a demo")
    code, _, err = run(capsys, "fit", str(tmp_path / "run*.csv"), "--out", tmp_path / "m.json", "--preset", "cubic")
    assert code == 0, err
    demos = captured["demos"]
    assert len(demos) == 2 and demos.dim == 3 and [d.source for d in demos] == ["run0.csv", "run1.csv"]
    np.testing.assert_allclose(demos[1].pos[0], [-2, 4, 1])
    assert captured["kwargs"] == {"preset": "cubic"}
    code, _, err = run(capsys, "fit", str(tmp_path / "run*.csv"), "--out", tmp_path / "m.json", "--warp", "none")
    assert code == 0, err
    assert captured["kwargs"] == {"warp": "none"}


def test_goal_tol_refuses_with_a_hint_and_accepts_when_raised(capsys, tmp_path, captured):
    paths = write_xy(tmp_path / "d", [(8, 2), (-6, 7)])
    shifted = np.loadtxt(paths[1], delimiter=",", skiprows=1) + [1.0, 0.0]   # 1 apart: each about 0.5 off the mean
    np.savetxt(paths[1], shifted, delimiter=",", header="x,y", comments="")
    argv = ["fit", *paths, "--dt", 0.1, "--out", tmp_path / "m.json"]
    code, _, err = run(capsys, *argv, "--goal-tol", 0.4, "--align-ends", "off")
    assert_one_error_line(code, err, "ends 0.49", "goal_tol = 0.4", "--goal-tol", need_try=True)
    code, _, err = run(capsys, *argv, "--goal-tol", 0.6, "--align-ends", "off")
    assert code == 0, err and len(captured["demos"]) == 2
    code, _, err = run(capsys, *argv, "--goal-tol", 0.4)       # the rule applies after preprocessing: aligned ends pass
    assert code == 0, err


def test_goal_tol_is_honoured_by_the_fit_itself(capsys, tmp_path):
    """A real fit (no stand-in): the value the error suggests is accepted end to end (ends not aligned)."""
    paths = write_xy(tmp_path / "d", [(8, 2), (-6, 7)], T=60)
    shifted = np.loadtxt(paths[1], delimiter=",", skiprows=1) + [3.0, 0.0]   # ends ~1.2 off the mean
    np.savetxt(paths[1], shifted, delimiter=",", header="x,y", comments="")
    argv = ["fit", *paths, "--dt", 0.1, "--components", 2, "--warp", "none", "--align-ends", "off", "--out", tmp_path / "m.json"]
    code, _, err = run(capsys, *argv)
    assert_one_error_line(code, err, "from the mean end point", "--goal-tol")
    suggested = re.search(r"e\.g\. ([\d.]+)", err).group(1)
    code, out, err = run(capsys, *argv, "--goal-tol", suggested)
    assert code == 0, err
    assert "certificate: passed" in out


def write_ms_reach(path, header="time,x,y,z,qx,qy,qz,qw"):
    """A robot-logger CSV: epoch milliseconds, a 2 s 3-D reach, orientation columns."""
    t = np.linspace(0, 2, 41)
    pos = np.outer(1 - t / 2, [0.3, -0.2, 0.5])
    quat = np.tile([0, 0, 0, 1], (len(t), 1))
    np.savetxt(path, np.column_stack([1.7e12 + 1e3 * t, pos, quat]), delimiter=",", header=header,
               comments="", fmt="%.15g")
    return path


def test_ms_stamps_and_orientation_columns_need_options(capsys, tmp_path, captured):
    """Time in ms and orientation columns: refused with the CLI options to use (no Python names); the
    quaternion columns make a pose file, read by the same time rules, Euler angles are refused."""
    path = write_ms_reach(tmp_path / "reach.csv")
    out = ["--out", tmp_path / "m.json"]
    code, _, err = run(capsys, "fit", path, *out)                            # a pose file: the same time check
    assert_one_error_line(code, err, "lasts 2000 s", "--time-units", need_try=True)
    euler = write_ms_reach(tmp_path / "rpy.csv", "time,x,y,z,roll,pitch,yaw,w")
    code, _, err = run(capsys, "fit", euler, *out)
    assert_one_error_line(code, err, "orientation columns ['roll', 'pitch', 'yaw']", "qw,qx,qy,qz",
                          "--columns x,y,z")
    code, _, err = run(capsys, "fit", path, "--columns", "x,y,z", *out)
    assert_one_error_line(code, err, "lasts 2000 s", "--time-units", need_try=True)
    assert "time_column=" not in err
    code, _, err = run(capsys, "fit", path, "--columns", "x,y,z", "--time-units", "ms", *out)
    assert code == 0, err
    demos = captured["demos"]
    assert demos.dim == 3 and demos[0].duration == pytest.approx(2.0)
    np.testing.assert_allclose(demos[0].vel[20], [-0.15, 0.1, -0.25], atol=1e-9)   # units per second
    code, _, err = run(capsys, "fit", path, "--time-units", "h", *out)
    assert code == 2 and "--time-units" in err
    no_time = tmp_path / "xy.csv"
    np.savetxt(no_time, np.outer(np.linspace(1, 0, 20), [1.0, 2.0]), delimiter=",", header="x,y", comments="")
    code, _, err = run(capsys, "fit", no_time, *out)
    assert_one_error_line(code, err, "no time column", "t_ms", "--dt STEP (sosdyn fit / plot)")
    assert "time_column" not in err


@pytest.mark.parametrize("argv, fragments", [
    (["{tmp}/empty"], ["holds no .csv or .npy file"]),
    (["{tmp}/nothing*.csv"], ["no file matches", "Try:"]),
    (["lasa:Angle", "--dt", "0.1"], ["apply to files, not to lasa:NAME"]),
])
def test_inputs_that_name_nothing_are_refused(capsys, tmp_path, captured, argv, fragments):
    (tmp_path / "empty").mkdir()
    code, _, err = run(capsys, "fit", *[a.format(tmp=tmp_path) for a in argv], "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, *fragments)
    assert captured == {}


def test_units_too_long_is_a_usage_error(capsys, tmp_path):
    code, _, err = run(capsys, "fit", "a.csv", "--units", "m" * 40)
    assert code == 2 and "at most 32 characters" in err


def test_help_shows_the_defaults(capsys):
    code, out, _ = run(capsys, "fit", "--help")
    text = " ".join(out.replace("│", " ").split())
    assert code == 0
    for default in (f"default: ({sd.CDSP().n_components}, or the preset's)", "default: model.json",
                    "--corrective-rounds", f"default: ({sd.CDSP().corrective_rounds}, or the preset's)",
                    "--warp", "<auto|none>", "default: (auto, or the preset's)",
                    "5% of the data's bounding-box diagonal"):
        assert default in text, default


def test_fit_a_shipped_set_prints_preprocessing_crossings_and_the_reproduction_table(capsys, tmp_path):
    code, out, err = run(capsys, "fit", "dataset:hammer", "--components", "2", "--warp", "none",
                         "--out", tmp_path / "m.json")
    assert code == 0, err
    text = " ".join(out.split())
    assert "sample k is placed at k * 0.01 s (assumed)" in text
    assert "smoothing: Savitzky-Golay, 13 samples" in text and "ends aligned to the mean end" in text
    assert "max 0.0215 m (inferred) (demo 7)" in text                # hammer's README: max end spread 0.0211
    rows = re.findall(r"^\s+(\d+)\s+([\d.e+-]+)\s+([\d.e+-]+)\s+([\d.e+-]+|never)\s+([\d.]+)\s+(yes|NO)$", out,
                      flags=re.MULTILINE)
    assert [int(r[0]) for r in rows] == list(range(10))
    assert all(float(r[1]) <= float(r[2]) for r in rows)
    assert json.loads((tmp_path / "m.json").read_text())["state"]["units_"] == "m (inferred)"


def test_fit_a_shipped_set_refuses_units_and_unknown_names(capsys, tmp_path):
    code, _, err = run(capsys, "fit", "dataset:hammer", "--units", "mm", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "apply to files; a shipped data set")
    code, _, err = run(capsys, "fit", "dataset:hamer", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "Did you mean hammer")


def test_progress_line_reads_step_cost_and_labelled_times():
    assert progress_line({"iteration": 2, "step": "metric", "cost": 12.5}, 0.214, 1.44) == \
        "step 3 (metric): cost 12.5 (0.21 s; 1.4 s since start)"
    assert progress_line({"iteration": 0, "step": "dynamics", "cost": 2.0, "round": 1}, 0.5, 3.0) == \
        "corrective round 1, step 1 (dynamics): cost 2 (0.50 s; 3.0 s since start)"
    assert progress_line({"iteration": 0, "step": "metric", "cost": 2.0, "round": 2, "warp": "none"}, 1, 3.0) == \
        "warp none, corrective round 2, step 1 (metric): cost 2 (1.00 s; 3.0 s since start)"


def test_iteration_cap_is_reported_only_when_hit(linear_demos_2d):
    rows = [{"step": "dynamics (M = I)", "cost": 10.0}]
    for old, new in ((10.0, 8.0), (8.0, 7.0)):
        rows += [{"step": "ica", "cost": old}, {"step": "dynamics", "cost": new}]
    assert capped(rows, 2, 1e-4) == "stopped at max_iter=2 with relative change 1.25e-01 > tol=0.0001"
    assert capped(rows, 3, 1e-4) is None                        # the cap was not reached
    assert capped(rows, 2, 0.2) is None                         # the last change met the tolerance
    model = sd.CDSP(n_components=2, warp="none", max_iter=1, tol=1e-12).fit(linear_demos_2d)
    assert model.iteration_cap(model.history_).startswith("stopped at max_iter=1 with relative change")
    assert sd.PoseCDSP(max_iter=2).iteration_cap(rows) == capped(rows, 2, 1e-4)     # the chart model's rule


def test_second_order_iteration_cap_reads_its_own_rows():
    """A "start" row, then one row per iteration (cost after it); the loop's test is relative to the new cost."""
    rows = [{"step": "start", "cost": 10.0}, {"step": "ica", "cost": 8.0}, {"step": "ica", "cost": 7.0}]
    model = sd.SecondOrderCDSP(field="mixture", max_iter=2)
    assert model.iteration_cap(rows) == "stopped at max_iter=2 with relative change 1.43e-01 > tol=0.0001"
    assert sd.SecondOrderCDSP(field="mixture", max_iter=3).iteration_cap(rows) is None      # stopped before the cap
    assert sd.SecondOrderCDSP(field="mixture", max_iter=2, tol=0.2).iteration_cap(rows) is None
    assert sd.SecondOrderCDSP().iteration_cap([]) is None                                 # tracking: no iterations


def test_fit_says_which_warp_was_kept_and_why(capsys, tmp_path):
    folder = tmp_path / "demos"
    write_xy(folder, [(8, 2), (-6, 7), (5, -8)], T=60)
    code, out, err = run(capsys, "fit", folder, "--dt", DT * 3, "--components", 2, "--smooth", "off", "--trim-rest", "off",
                         "--align-ends", "off", "--out", tmp_path / "m.json")
    assert code == 0, err
    scores = sd.CDSP(n_components=2).fit(sd.load_demos(sorted(folder.glob("*.csv")), dt=DT * 3)).warp_scores_
    kept = min(scores, key=scores.get)
    assert f"-> kept {kept} (the lowest)" in out
    for name, score in scores.items():
        assert f"{name} {score:.4g}" in out

"""Logs as they come through ``sosdyn fit`` (issue 34 item 3, issue 35 items 6 and 8): the note about
repeated time stamps on one line, one rule for the ends in Python and the CLI, a shipped set read
alone, tiny time steps refused once."""
import importlib

import numpy as np
import pytest

import cli_support
import sosdyn as sd
from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.lfd.data.files import load_demos

LIMITS = importlib.import_module("sosdyn.limits")      # the module (sosdyn.limits is also a function)


def reach(path, header, t, *columns):
    np.savetxt(path, np.column_stack([t, *columns]), delimiter=",", header=",".join(header), comments="")
    return path



def test_the_cli_prints_the_note_on_one_line(capsys, tmp_path, monkeypatch):
    t = np.round(np.linspace(0.0, 1.0, 60), 2)
    t[10] = t[9]
    paths = [reach(tmp_path / f"m{k}.csv", ["t", "x", "y"], t, np.cos(3 * t) + k, np.sin(3 * t)) for k in range(2)]
    monkeypatch.setattr(sd.CDSP, "fit", lambda self, demos: (_ for _ in ()).throw(InputError("stopped here")))
    code, out, err = cli_support.run(capsys, "fit", *paths, "--out", tmp_path / "m.json")
    assert code == 1 and "stopped here" in err
    assert ("note: repeated time stamps in 2 of 2 demonstrations (first: m0.csv): one sample per stamp kept, 2 "
            "identical row(s) dropped and 0 differing row(s) averaged into their stamp's sample.") in out.splitlines()
    assert "UserWarning" not in out + err and "warnings.warn" not in out + err


def pouring_files():
    return sorted((DATASETS_DIR / "pouring").glob("demo_*.csv"))


def test_one_rule_for_the_ends_in_python_and_the_cli(capsys, tmp_path, monkeypatch):
    """The 63 real pourings: sd.load_demos refused them ('do not share a goal', ends checked before the
    alignment with another threshold) while sosdyn fit fitted them. Now the loaders leave the ends to
    the check after preprocessing, in both."""
    demos = load_demos(pouring_files(), columns="x,y,z")             # before: DemonstrationError
    with pytest.raises(DemonstrationError, match="do not share a goal.*Try: align the ends first"):
        sd.check_demonstrations(demos)                               # the rule, before preprocessing
    prepared, _ = sd.preprocess(demos)
    python = sd.CDSP.prepare(demos)[0]
    assert len(sd.check_demonstrations(prepared)) == len(python) == 63
    seen = {}
    monkeypatch.setattr(sd.CDSP, "fit", lambda self, d: seen.setdefault("demos", d) and
                        (_ for _ in ()).throw(InputError("stopped here")))
    code, _, err = cli_support.run(capsys, "fit", *pouring_files(), "--columns", "x,y,z", "--out", tmp_path / "m.json")
    assert "stopped here" in err and len(seen["demos"]) == 63
    for d_cli, d_py in zip(seen["demos"], python):
        np.testing.assert_array_equal(d_cli.pos, d_py.pos)
    # the same refusal both ways when the ends are not aligned
    code, _, err = cli_support.run(capsys, "fit", *pouring_files(), "--columns", "x,y,z", "--align-ends", "off",
                                   "--out", tmp_path / "m.json")
    with pytest.raises(DemonstrationError) as refused:
        sd.CDSP.prepare(demos, align=False)
    cli_support.assert_one_error_line(code, err, str(refused.value).split(";")[0])


def test_a_shipped_set_mixed_with_other_inputs_is_refused_truthfully(capsys, tmp_path):
    """Before: 'demonstration file not found: dataset:crossing/e'."""
    code, _, err = cli_support.run(capsys, "fit", "dataset:crossing/e", "lasa:Sshape", "--out", tmp_path / "m.json")
    cli_support.assert_one_error_line(code, err, "dataset:crossing/e names a shipped set, and a shipped set is read alone",
                                      "Try: sosdyn fit dataset:crossing/e on its own", need_try=True)


def test_tiny_time_steps_are_one_typed_refusal(capsys, tmp_path):
    """Before: sosdyn fit --dt 1e-300 printed 10 numpy warning lines, then a ValueError."""
    t = np.linspace(0.0, 1.0, 50)
    paths = []
    for k in range(2):
        paths.append(tmp_path / f"p{k}.csv")
        np.savetxt(paths[-1], np.column_stack([np.cos(2 * t) + k, np.sin(2 * t)]), delimiter=",", header="x,y",
                   comments="")
    code, out, err = cli_support.run(capsys, "fit", *paths, "--dt", 1e-300, "--out", tmp_path / "m.json")
    cli_support.assert_one_error_line(code, err, "the velocities reach", "above 1e+100", "Try: the time step in s")
    assert out == ""



def test_the_limits_are_raised_for_the_command_through_the_environment(capsys, tmp_path, monkeypatch):
    """The CLI's message said sosdyn.set_limits(max_bytes=...) bounds the work, a Python call a shell
    user cannot make; SOSDYN_<LIMIT> in the environment is the command's way, and the message says so."""
    t = np.linspace(0.0, 1.0, 400)
    path = reach(tmp_path / "a.csv", ["t", "x", "y"], t, np.cos(t), np.sin(t))
    for value, fragments in (("1000", ("over the limit of 1000 B", "SOSDYN_MAX_BYTES=... in the environment")),
                             ("lots", ("the environment variable SOSDYN_MAX_BYTES = 'lots' is not an integer",))):
        monkeypatch.setenv("SOSDYN_MAX_BYTES", value)
        monkeypatch.setattr(LIMITS, "_current", None)          # a new session: the limits are read again
        code, _, err = cli_support.run(capsys, "fit", path, "--out", tmp_path / "m.json")
        cli_support.assert_one_error_line(code, err, *fragments)
    monkeypatch.setenv("SOSDYN_MAX_BYTES", "12345")
    monkeypatch.setattr(LIMITS, "_current", None)
    assert sd.get_limits().max_bytes == 12345


def test_late_arrivals_are_said_under_the_certificate(capsys, tmp_path, monkeypatch):
    """The caution stands right under 'certificate: passed' (before: a bare warning after the table)."""
    t = np.linspace(0.0, 2.0, 60)
    paths = [reach(tmp_path / f"r{k}.csv", ["t", "x", "y"], t, (1 - t / 2) ** 2 * (3 + k), (1 - t / 2) ** 2 * (1 - k))
             for k in range(2)]

    def late(self, demos):
        return [{"demo": i, "source": d.source, "mean_dev": 0.0, "max_dev": 0.0, "arrival_s": np.inf,
                 "duration_s": d.duration, "final_error": 1.0, "at_goal": False} for i, d in enumerate(demos)]
    monkeypatch.setattr(sd.CDSP, "score", late)
    code, out, err = cli_support.run(capsys, "fit", *paths, "--components", 1, "--warp", "none", "--out", tmp_path / "m.json")
    assert code == 0, err
    lines = out.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("certificate: passed"))
    assert lines[k + 1].startswith("arrival: 2 of 2 reproductions do not reach the goal within twice"), lines[k + 1]
    assert "eventual arrival, not arrival within the demonstrations' time" in lines[k + 1]
    assert any(line.split()[:1] == ["0"] and "never" in line for line in lines)     # the table's time to the goal

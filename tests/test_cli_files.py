"""Which files ``sosdyn fit`` reads (issue 23, item 5): a name that exists is a file, never a
pattern; dotfiles in folders and patterns are skipped."""
from __future__ import annotations

import os

import numpy as np
import pytest
from cli_support import assert_one_error_line, run

from sosdyn.cli.paths import demo_inputs
from sosdyn.errors import InputError


def write(path, start=(3.0, 1.0), end=(0.0, 0.0)):
    t = np.linspace(0, 2, 40)
    pos = np.outer(1 - t / 2, start) + np.outer(t / 2, end)
    np.savetxt(path, np.column_stack([t, pos]), delimiter=",", header="t,x,y", comments="")
    return path


def test_an_existing_name_with_brackets_is_that_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in ("run[1].csv", "run[2].csv", "run1.csv", "run2.csv"):
        write(tmp_path / name)
    assert [p.name for p in demo_inputs(["run[1].csv", "run[2].csv"])] == ["run[1].csv", "run[2].csv"]
    assert [p.name for p in demo_inputs([str(tmp_path / "run[2].csv")])] == ["run[2].csv"]
    assert [p.name for p in demo_inputs(["run[12].csv"])] == ["run1.csv", "run2.csv"]     # no such file: a pattern
    os.remove("run1.csv")
    os.remove("run2.csv")
    assert [p.name for p in demo_inputs(["run[1].csv"])] == ["run[1].csv"]               # alone: still found


def test_dotfiles_are_skipped_in_folders_and_patterns(tmp_path):
    demos = tmp_path / "demos"
    demos.mkdir()
    write(demos / "a.csv")
    (demos / "._a.csv").write_bytes(b"\x00\x05\x16\x07 macOS resource fork")
    (demos / ".b.csv").write_text("not a demo")
    assert [p.name for p in demo_inputs([str(demos)])] == ["a.csv"]
    assert [p.name for p in demo_inputs([str(demos / "*.csv")])] == ["a.csv"]
    assert [p.name for p in demo_inputs([str(demos / ".*.csv")])] == ["._a.csv", ".b.csv"]   # asked for
    assert [p.name for p in demo_inputs([str(demos / "._a.csv")])] == ["._a.csv"]            # named


def test_a_folder_of_dotfiles_only_holds_nothing(tmp_path):
    (tmp_path / "._a.csv").write_text("x")
    with pytest.raises(InputError, match="holds no .csv or .npy file"):
        demo_inputs([str(tmp_path)])


def test_fit_of_a_folder_with_a_resource_fork_reads_the_demos_only(capsys, tmp_path, monkeypatch):
    """End to end, with the fit stopped at the goal check: the resource fork is never parsed."""
    demos = tmp_path / "demos"
    demos.mkdir()
    write(demos / "a.csv", (3.0, 1.0))
    write(demos / "b.csv", (-2.0, 4.0), end=(0.5, 0.0))
    (demos / "._a.csv").write_bytes(b"\x00\x05\x16\x07\x00\x02\x00\x00Mac OS X")
    code, _, err = run(capsys, "fit", demos, "--goal-tol", 0.1, "--align-ends", "off", "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "(a.csv) of 'demos' ends 0.25", "goal_tol = 0.1")   # both read, no fork
    assert "._a.csv" not in err

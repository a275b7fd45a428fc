"""The command line's guards: --out checked before any work, every failure one line and exit 1,
``report`` refusing what is not a results file. No fit runs here: each guard fires before
the learner would be called, and stand-ins record that it never was."""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys

import pytest

import cli_support
import sosdyn as sd
from sosdyn.cli import paths as cli_paths
from sosdyn.cli import error_line, main
from sosdyn.errors import DemonstrationError, InputError, ModelFileError
from sosdyn.lfd.model.fileformat import FORMAT, VERSION
from sosdyn.limits import json_text_depth

TRY_RESULTS = "Try: pass the results.json"
run = cli_support.run
assert_one_error_line = functools.partial(cli_support.assert_one_error_line, need_try=True)


@pytest.fixture
def never_called(monkeypatch):
    """Stand-ins for every loader/learner: calling one fails the test."""
    calls = []

    def refuse(name):
        def stand_in(*args, **kwargs):
            calls.append(name)
            raise AssertionError(f"{name} was called although a guard should have stopped the command")
        return stand_in

    for name in ("load_demos", "load_lasa", "load_model", "CDSP"):
        monkeypatch.setattr(sd, name, refuse(name), raising=False)
    return calls


@pytest.fixture
def demos(tmp_path):
    """Two demonstration CSVs; returns (paths, their bytes)."""
    paths = []
    for i in range(2):
        path = tmp_path / f"d{i}.csv"
        path.write_text(f"t,x1,x2\n0,{i + 1},1\n1,0,0\n")
        paths.append(path)
    return paths, [p.read_bytes() for p in paths]


# ---------------------------------------------------------------- --out guards: fit

def test_fit_out_is_a_demo(capsys, demos, never_called):
    paths, before = demos
    code, _, err = run(capsys, "fit", *paths, "--out", paths[0])
    assert_one_error_line(code, err, f"--out {paths[0]} is the demonstration file", "destroy the input")
    assert [p.read_bytes() for p in paths] == before and never_called == []


@pytest.mark.parametrize("alias", ["symlink", "hardlink", "dotted"])
def test_fit_out_is_a_demo_under_another_name(capsys, tmp_path, demos, never_called, alias):
    paths, before = demos
    target = paths[1]
    if alias == "symlink":
        out = tmp_path / "link.json"
        out.symlink_to(target)
    elif alias == "hardlink":
        out = tmp_path / "hard.json"
        os.link(target, out)
    else:
        (tmp_path / "sub").mkdir()
        out = tmp_path / "sub" / ".." / target.name
    code, _, err = run(capsys, "fit", *paths, "--out", out)
    assert_one_error_line(code, err, f"is the demonstration file {target}")
    assert [p.read_bytes() for p in paths] == before and never_called == []


@pytest.mark.parametrize("where, fragment", [
    ("missing/m.json", "the folder {tmp}/missing does not exist"),
    ("d0.csv/m.json", "{tmp}/d0.csv is a file, not a folder"),
    (".", "is a folder"),
])
def test_fit_bad_out_fails_before_loading(capsys, tmp_path, demos, never_called, where, fragment):
    paths, before = demos
    code, _, err = run(capsys, "fit", *paths, "--out", tmp_path / where)
    assert_one_error_line(code, err, fragment.format(tmp=tmp_path))
    assert never_called == [] and [p.read_bytes() for p in paths] == before
    assert not (tmp_path / "missing").exists()


def test_fit_out_in_a_folder_without_write_permission(capsys, monkeypatch, tmp_path, demos, never_called):
    locked = tmp_path / "locked"
    locked.mkdir()
    real_access = os.access
    monkeypatch.setattr(cli_paths.os, "access", lambda p, mode: False if str(p) == str(locked) else real_access(p, mode))
    code, _, err = run(capsys, "fit", *demos[0], "--out", locked / "m.json")
    assert_one_error_line(code, err, f"cannot write in the folder {locked}")
    assert never_called == [] and list(locked.iterdir()) == []


def test_fit_out_is_a_read_only_file(capsys, monkeypatch, tmp_path, demos, never_called):
    old = tmp_path / "old.json"
    old.write_bytes(b"previous model")
    real_access = os.access
    monkeypatch.setattr(cli_paths.os, "access",
                        lambda p, mode: False if str(p) == str(old) and mode & os.W_OK else real_access(p, mode))
    code, _, err = run(capsys, "fit", *demos[0], "--out", old)
    assert_one_error_line(code, err, f"--out {old} exists and is read-only")
    assert never_called == [] and old.read_bytes() == b"previous model"


def test_fit_lasa_checks_out_before_loading(capsys, tmp_path, never_called):
    code, _, err = run(capsys, "fit", "lasa:Leaf_1", "--out", tmp_path / "nope" / "leaf.json")
    assert_one_error_line(code, err, "does not exist")
    assert never_called == []


@pytest.mark.parametrize("argv, option", [
    (["--seed", "-1"], "--seed"), (["--seed", str(2**32)], "--seed"),
    (["--gamma", "0"], "--gamma"), (["--gamma", "nan"], "--gamma"), (["--components", "0"], "--components"),
])
def test_fit_bad_option_values_are_usage_errors(capsys, demos, never_called, argv, option):
    code, _, err = run(capsys, "fit", *demos[0], *argv)
    assert code == 2 and option in err and "Traceback" not in err
    assert never_called == []


# ------------------------------------------------------------ --out guards: rollout

@pytest.fixture
def model_file(tmp_path):
    """A stand-in model file (the guards never read it)."""
    path = tmp_path / "m.json"
    path.write_text('{"format": "sosdyn-cdsp"}\n')
    return path


@pytest.mark.parametrize("alias", ["same", "symlink"])
def test_rollout_out_is_the_model(capsys, tmp_path, model_file, never_called, alias):
    before = model_file.read_bytes()
    out = model_file
    if alias == "symlink":
        out = tmp_path / "traj.csv"
        out.symlink_to(model_file)
    code, _, err = run(capsys, "rollout", model_file, "--from", "1,2", "--out", out)
    assert_one_error_line(code, err, f"is the model file {model_file}")
    assert model_file.read_bytes() == before and never_called == []


def test_rollout_out_in_missing_folder(capsys, tmp_path, model_file, never_called):
    code, _, err = run(capsys, "rollout", model_file, "--from", "1,2", "--out", tmp_path / "no" / "t.csv")
    assert_one_error_line(code, err, "does not exist")
    assert never_called == [] and not (tmp_path / "no").exists()


@pytest.mark.parametrize("argv", [["--duration", "0"], ["--duration", "nan"], ["--dt", "-1"], ["--dt", "inf"]])
def test_rollout_bad_times_are_usage_errors(capsys, model_file, never_called, argv):
    code, _, err = run(capsys, "rollout", model_file, "--from", "1,2", *argv)
    assert code == 2 and argv[0] in err and "Traceback" not in err
    assert never_called == []


# ------------------------------------------------------------------ report command

RESULTS_OK = {"meta": {"seed": 0}, "findings": []}


@pytest.fixture
def out_dir(tmp_path):
    """An existing report folder with sentinel files that must stay byte-identical."""
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "index.html").write_bytes(b"<p>old report</p>")
    (folder / "report.pdf").write_bytes(b"%PDF old")
    return folder


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.parametrize("content, fragment", [
    (json.dumps({"format": FORMAT, "version": VERSION, "params": {}, "state": {}, "sha256": "0" * 64}),
     "not a sosdyn results file (no 'meta' or 'findings'; unexpected key(s) 'format', 'params'"),
    ("{}", "not a sosdyn results file (no 'meta' or 'findings')"),
    ("[]", "holds a JSON array, expected a JSON object"),
    ("null", "holds a JSON null, expected a JSON object"),
    (json.dumps({"meta": {}}), "(no 'findings')"),
    (json.dumps({"meta": {}, "findings": {}}), "'findings' should be a JSON array, not object"),
    (json.dumps({"meta": [], "findings": [1]}), "'meta' should be a JSON object, not array; 'findings' holds non-objects"),
    (json.dumps({**RESULTS_OK, "timings": 3}), "'timings' should be a JSON object, not number"),
    ("{not json", "is not valid JSON"),
    ("[" * 65 + "]" * 65, "nesting depth of"),
    ("[" * 100_000 + "]" * 100_000, "is 1e+05, over the limit max_json_depth=64"),
])
def test_report_refuses_what_is_not_a_results_file(capsys, tmp_path, out_dir, content, fragment):
    results = tmp_path / "results.json"
    results.write_text(content)
    before = _snapshot(out_dir)
    code, _, err = run(capsys, "report", "--results", results, "--out", out_dir)
    assert_one_error_line(code, err, fragment)
    assert _snapshot(out_dir) == before


def test_report_refuses_without_creating_the_folder(capsys, tmp_path):
    results = tmp_path / "results.json"
    results.write_text("{}")
    code, _, err = run(capsys, "report", "--results", results, "--out", tmp_path / "new")
    assert_one_error_line(code, err, TRY_RESULTS)
    assert not (tmp_path / "new").exists()


def test_report_file_size_cap(capsys, tmp_path, out_dir):
    results = tmp_path / "results.json"
    results.write_text(json.dumps({**RESULTS_OK, "methods": {"x" * 500: None}}))
    before = _snapshot(out_dir)
    with sd.limits(max_file_bytes=200):
        code, _, err = run(capsys, "report", "--results", results, "--out", out_dir)
    assert_one_error_line(code, err, f"the size of {results} in bytes is 5", "max_file_bytes=200")
    assert _snapshot(out_dir) == before


def test_report_refuses_figures_outside_its_folder(capsys, tmp_path, out_dir):
    (tmp_path / "secret.png").write_bytes(b"\x89PNG not really")
    results = tmp_path / "in" / "results.json"
    results.parent.mkdir()
    results.write_text(json.dumps({"meta": {}, "findings": [], "figures": {"x": {"png": "../secret.png"}}}))
    before = _snapshot(out_dir)
    code, _, err = run(capsys, "report", "--results", results, "--out", out_dir)
    assert_one_error_line(code, err, "'x': ../secret.png lies outside the report folder")
    assert _snapshot(out_dir) == before


@pytest.mark.parametrize("name", ["index.html", "report.pdf"])
def test_report_never_overwrites_its_results_file(capsys, tmp_path, name):
    folder = tmp_path / "r"
    folder.mkdir()
    results = folder / name
    results.write_text(json.dumps(RESULTS_OK))
    before = _snapshot(folder)
    code, _, err = run(capsys, "report", "--results", results, "--out", folder)
    assert_one_error_line(code, err, f"--out {results} is the results file {results}")
    assert _snapshot(folder) == before


def test_report_out_is_a_file(capsys, tmp_path):
    results = tmp_path / "results.json"
    results.write_text(json.dumps(RESULTS_OK))
    before = results.read_bytes()
    code, _, err = run(capsys, "report", "--results", results, "--out", results)
    assert_one_error_line(code, err, f"{results} is a file, not a folder")
    assert results.read_bytes() == before


def test_report_out_two_levels_missing(capsys, tmp_path):
    results = tmp_path / "results.json"
    results.write_text(json.dumps(RESULTS_OK))
    code, _, err = run(capsys, "report", "--results", results, "--out", tmp_path / "a" / "b")
    assert_one_error_line(code, err, "does not exist")
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("text, depth", [
    (b"1", 0), (b"{}", 1), (b'[[1, [2]], {"a": 3}]', 3),
    (b'{"a": "[[[[\\"[[", "b": [{}]}', 3),          # brackets inside strings (and \") do not count
    (b"[" * 70 + b"]" * 70, 70),
])
def test_json_text_depth(text, depth):
    assert json_text_depth(text, chunk=4) == depth == json_text_depth(text)


# -------------------------------------------------- every failure is one line, exit 1

@pytest.fixture
def fit_raises(monkeypatch, demos):
    """``fit d0.csv d1.csv`` whose loader raises the given exception."""
    def arrange(exc):
        def load(paths, **read):
            raise exc
        monkeypatch.setattr(sd, "load_demos", load, raising=False)
        return [*demos[0]]
    return arrange


@pytest.mark.parametrize("exc, expected", [
    (ValueError("The 'random_state' parameter must be an int in [0, 4294967295]. Got -1 instead."),
     "Got -1 instead. Try: check the options (sosdyn COMMAND --help)"),
    (PermissionError(13, "Permission denied", "/x/m.json"), "Permission denied: /x/m.json. Try: check the permissions"),
    (IsADirectoryError(21, "Is a directory", "/x"), "Is a directory: /x. Try: check the path."),
    (RecursionError("maximum recursion depth exceeded while decoding a JSON array"),
     "input nested too deeply (maximum recursion depth exceeded while decoding a JSON array). Try:"),
    (MemoryError(), "out of memory. Try: smaller inputs"),
    (DemonstrationError("demo 2 has NaN at row 7.\nFirst bad value: x1.\nTry: clean the file."),
     "demo 2 has NaN at row 7. First bad value: x1. Try: clean the file."),
    (ModelFileError("m.json: the certificate does not check out.\nmin Gram eig -1e-3\nmax eig 0.2"),
     "does not check out. min Gram eig -1e-3; max eig 0.2. Try: rerun with --debug"),
    (ModelFileError("m.json fails its checksum"), "m.json fails its checksum. Try: rerun with --debug"),
])
def test_error_becomes_one_line(capsys, fit_raises, tmp_path, exc, expected):
    code, _, err = run(capsys, "fit", *fit_raises(exc), "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, expected)
    assert error_line(exc) == err.strip().removeprefix("error: ")


def test_sosdyn_debug_env_reraises(capsys, monkeypatch, fit_raises, tmp_path):
    monkeypatch.setenv("SOSDYN_DEBUG", "1")
    with pytest.raises(InputError, match="bad data"):
        main(["fit", *map(str, fit_raises(InputError("bad data"))), "--out", str(tmp_path / "m.json")])
    monkeypatch.setenv("SOSDYN_DEBUG", "0")
    code, _, err = run(capsys, "fit", *fit_raises(InputError("bad data")), "--out", tmp_path / "m.json")
    assert_one_error_line(code, err, "bad data")


def test_real_process_deep_json(tmp_path):
    """In a real process (no test harness catching anything): one line, no traceback, exit 1."""
    results = tmp_path / "results.json"
    results.write_text("[" * 10_000 + "]" * 10_000)
    proc = subprocess.run([sys.executable, "-m", "sosdyn.cli", "report", "--results", str(results),
                           "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("error: the nesting depth of") and "max_json_depth=64" in line
    assert not (tmp_path / "out").exists()

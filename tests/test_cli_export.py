"""`sosdyn export`, `sosdyn plot` and `sosdyn --version`: real models, in-process runs."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations

from cli_support import run


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


def test_export_refuses_to_overwrite_its_input(capsys, saved):
    model_path = saved[2][0]
    before = model_path.read_bytes()
    code, _, err = run(capsys, "export", str(model_path), "--to", "python", "--out", str(model_path))
    assert code == 1 and "would destroy the input" in err
    assert model_path.read_bytes() == before


def test_export_unknown_target_is_a_usage_error(capsys, saved, tmp_path):
    code, _, err = run(capsys, "export", str(saved[2][0]), "--to", "rust", "--out", str(tmp_path / "x.rs"))
    assert code == 2 and "rust" in err


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

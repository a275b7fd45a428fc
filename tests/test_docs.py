"""The documentation site builds offline with --strict, and its key pages carry their content.

Skipped when the `docs` extra (mkdocs, mkdocs-material, mkdocstrings) is not installed.
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mkdocs", reason="mkdocs (the `docs` extra) is not installed")
pytest.importorskip("material", reason="mkdocs-material (the `docs` extra) is not installed")
pytest.importorskip("mkdocstrings_handlers.python", reason="mkdocstrings[python] is not installed")

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-f",
                           str(ROOT / "mkdocs.yml"), "-d", str(out)],
                          cwd=out, env=env, capture_output=True, text=True, timeout=120,
                          check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


def page(site: Path, name: str) -> str:
    path = site / name / "index.html" if name else site / "index.html"
    assert path.exists(), f"{name or 'index'} page missing; built: {sorted(p.name for p in site.iterdir())}"
    return path.read_text(encoding="utf-8")


def test_narrative_pages(site):
    assert "sum-of-squares" in page(site, "").lower()
    for name, text in [("theory", "collapses"), ("errors", "UnverifiedSolutionError"),
                       ("interfaces", "Demonstrations"), ("model-file", "sosdyn-cdsp"), ("findings", "16 694 to 7 479")]:
        assert text in page(site, name), name


def test_examples_are_included_from_the_scripts(site):
    html = page(site, "examples")
    for script in sorted((ROOT / "examples").glob("*.py")):
        first_code_line = next(line for line in script.read_text().splitlines() if line.startswith("import "))
        assert first_code_line.split()[1] in html, script.name
    assert "load_demos" in html and "add_nonneg_on" in html and "rigorous=True" in html


@pytest.mark.parametrize("module, member", [
    ("sosdyn", "sosdyn.CDSP"), ("poly", "sosdyn.poly.Polynomial"), ("sos", "sosdyn.sos.SOSProgram"),
    ("lfd", "sosdyn.lfd.load_demos"), ("evaluation", "sosdyn.evaluation.metrics"),
    ("report", "sosdyn.report.figures.streamlines.streamlines")])
def test_api_reference(site, module, member):
    assert f'id="{member}"' in page(site, f"api/{module}")


def test_offline(site):
    """No page pulls scripts, styles or fonts from the network."""
    for html in site.rglob("*.html"):
        text = html.read_text(encoding="utf-8")
        assert 'src="http' not in text and "fonts.googleapis" not in text, html.name


def test_docstrings_render_without_sphinx_roles_and_cdsp_parameters_as_a_list(site):
    """The hook docs_hooks/roles.py turns :mod:`x` into code; CDSP's parameters are list items."""
    for html in (site / "api").rglob("*.html"):
        text = html.read_text(encoding="utf-8")
        assert not re.search(r":(mod|func|class|meth|data|attr):<code>", text), html
    lfd = page(site, "api/lfd")
    cdsp = lfd[lfd.index('id="sosdyn.lfd.CDSP"'):]
    assert "<li><code>n_components</code> (int or \"bic\")" in cdsp and "<li><code>warp</code>" in cdsp

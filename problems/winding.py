"""Held-out accuracy on the synthesised winding set (``make winding``, issue 36).

The protocol is :mod:`sosdyn.evaluation.realdata`'s (first ceil(4N/7) = 4 of the 7 demos train, the rest
test; preprocessing chosen on the training demos; explicit Euler at 0.01 s from each test demo's 20th
kept sample; every reproduction read at its test demo's own period before the cumulative DTW,
:func:`sosdyn.evaluation.realdata.at_period`, so the curves compared are sampled alike; arrival, excursion
and final error are read from the whole 0.01 s rollout). Copy: the nearest training demo's DTWD.

Methods: ``CDSP before`` is the default as it was before issue 36 (``warp="auto"`` choosing among the
plain fit and the two radial warps by the same rule, :func:`before`; the posterior gating, no speed floor); ``CDSP default`` is ``sd.CDSP()``
(random_state 0); ``CDSP isotonic + twist`` is one fixed warp: the isotonic target matched to every demo,
then a twist about the goal of shear bound K = 3 (docs/theory.md). One JSON per (shape, method) is
cached in ``<out>/cache``; ``<out>`` = ``reports/winding``: ``results.json``, ``index.html`` and one
figure per shape. Targets: DTWD <= 3x copy, certified, excursion <= 0.25 of the training box's
diagonal, arrival within 2x the demo's remaining duration (no stall). ``--quick``: two shapes, small fits.
"""
from __future__ import annotations

import html
import json
import time
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import SolverError
from sosdyn.evaluation import realdata
from sosdyn.lfd.data.datasets import WINDING_SHAPES
from sosdyn.lfd.fit.pipeline import block_field, candidate_fits
from sosdyn.lfd.fit.rounds import warp_choice
from sosdyn.lfd.fit.warp import AUTO_WARPS
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import METHOD_COLORS, data_bounds, new_figure, styled

from .jobs import parallel_map
from .jsonio import write_json
from .lasa_warp import cdsp_key
from .real_data import QUICK, cached_job, parser
from .real_data_report import fmt
from .settings import REPORTS

OUT = REPORTS / "winding"
CACHE_VERSION = 2              # 2: CDSP before with the posterior gating and no speed floor
SETS = tuple(f"winding/{s}" for s in WINDING_SHAPES)
TWIST = {"n_maps": 60, "decay": 1.0, "target": "isotonic", "match": "each", "twist": 3.0}
METHODS = {"CDSP before": {"gating": "posterior", "speed_floor": "none"}, "CDSP default": {},
           "CDSP isotonic + twist": {"warp": TWIST}}
COLORS = {"CDSP before": "#E69F00", "CDSP default": METHOD_COLORS["cdsp"], "CDSP isotonic + twist": "#CC79A7"}
BEFORE_WARPS = {k: AUTO_WARPS[k] for k in ("60 maps, decay 0.75", "60 maps, decay 1")}
TARGET_RATIO, TARGET_EXCURSION, TARGET_ARRIVAL = 3.0, 0.25, 2.0
QUICK_SETS = ("winding/hook", "winding/nearhook")
PROTOCOL = ("Held-out, after ds-opt's protocol (sosdyn.evaluation.realdata): the first 4 of the 7 demos of each "
            "shape train, the other 3 test; the training demos preprocessed with sosdyn.preprocess's defaults "
            "(chosen on them), the test demos only trimmed of rest; every 2nd sample; explicit Euler (dt 0.01 s) from "
            "each test demo's 20th kept sample until rest; each reproduction read at its test demo's own period "
            "(linear interpolation in time) before the cumulative DTW, so the curves compared are sampled alike; "
            "DTWD against copying the nearest training demo. Random state 0.")


def before(train, settings: dict) -> sd.CDSP:
    """The default before issue 36: the fit path of ``warp="auto"`` with its former candidates
    (the plain fit and BEFORE_WARPS; no isotonic target, no escalation), as a CDSP."""
    model = sd.CDSP(**settings)
    params = dict(model.get_params(), random_state=settings["random_state"])
    kept, scores = warp_choice(candidate_fits(train, {"none": None, **BEFORE_WARPS}, params, None), train,
                               block_field)
    model.__dict__.update(vars(kept), warp_scores_=scores, floor_=None)
    return model


def fitter(method: str, quick: bool):
    settings = dict(METHODS[method], random_state=0, **(QUICK if quick else {}))
    if method == "CDSP before":
        return lambda train: before(train, settings)
    return lambda train: sd.CDSP(**settings).fit(train)


def evaluate(fit_fn, demos) -> dict:
    """The protocol (module docstring) on one set: :func:`sosdyn.evaluation.realdata.evaluate_set`
    (reproductions read at the test demos' period) with the kept warp candidate and each candidate's
    training deviation."""
    fitted = []
    out = realdata.evaluate_set(lambda train: fitted.append(fit_fn(train)) or fitted[-1], demos)
    if out["failure"]:
        raise SolverError(out["failure"])       # an entry with "error" (problems.real_data.cached_job)
    scores = getattr(fitted[-1], "warp_scores_", {})
    return dict(out, kept=min(scores, key=scores.get) if scores else None, warp_scores=scores)


def run_job(name: str, method: str, quick: bool, cache_dir: Path, force: bool) -> dict:
    key = {"version": CACHE_VERSION, "set": name, "method": cdsp_key(dict(METHODS[method], **(QUICK if quick else {}))),
           "quick": quick}
    return cached_job(cache_dir, name, method, quick, key, force, lambda: evaluate(fitter(method, quick),
                                                                                   sd.load_dataset(name)))


def job_label(e: dict) -> str:
    if e["error"]:
        return f"{e['set']:<18} {e['method']:<22} FAILED: {e['error'][:120]}"
    src = "cache" if e["from_cache"] else f"fit {e['fit_s']:.1f} s"
    return (f"{e['set']:<18} {e['method']:<22} DTWD/copy {e['ratio']:6.2f}  excursion {e['excursion']:.3f}  "
            f"arrival {e['arrival_ratio']:.2f}x  certified {e['certified']}  kept {e['kept']}  ({src})")


def met(e: dict) -> bool:
    """Every target of issue 36 for the winding shapes."""
    return not e["error"] and e["ratio"] <= TARGET_RATIO and e["certified"] and \
        e["excursion"] <= TARGET_EXCURSION and e["arrival_ratio"] <= TARGET_ARRIVAL


def _panel(ax, demos, paths, color, title):
    """Training demos (grey), test demos (black, dashed), ``paths`` in ``color``, the goal; equal axes
    on the demos' box + 25 % (paths leaving it are cut)."""
    train, test = realdata.split_first(demos)
    for d in train:
        ax.plot(*d.pos.T, color="0.75", lw=0.7)
    for d in test:
        ax.plot(*d.pos.T, color="black", lw=0.9, ls="--")
    for p in paths or []:
        ax.plot(*np.asarray(p, dtype=float).T, color=color, lw=1.2)
    ax.plot(*train.goal, marker="*", ms=9, color="black", ls="none")
    x0, x1, y0, y1 = data_bounds([d.pos for d in demos], pad=0.25, square=True)
    ax.set(xlim=(x0, x1), ylim=(y0, y1), aspect="equal", title=title)


@styled
def shape_figure(name: str, entries: dict, out_dir: Path) -> Path:
    """One panel per method: the demos and the method's reproductions from the test starts."""
    demos, methods = sd.load_dataset(name), list(entries)
    fig = new_figure(3.3 * len(methods), 3.6)
    for k, m in enumerate(methods):
        e = entries[m]
        title = f"{m}: failed" if e["error"] else f"{m}: {e['ratio']:.2f}× copy"
        _panel(fig.add_subplot(1, len(methods), k + 1), demos, e.get("paths"), COLORS[m], title)
    fig.suptitle(f"{name} (px): 4 training demos (grey), 3 test demos (dashed), reproductions from the test starts")
    return save_figure(fig, Path(out_dir) / "figures" / name.replace("/", "__"), dpi=100)["png"]


@styled
def overview(per_set: dict, method: str, out_dir: Path) -> Path:
    """Every shape in one figure: ``method``'s reproductions (``per_set``: {set: {method: entry}})."""
    fig = new_figure(11, 11)
    for k, (s, d) in enumerate(per_set.items()):
        e = d[method]
        _panel(fig.add_subplot(3, (len(per_set) + 2) // 3, k + 1), sd.load_dataset(s), e.get("paths"),
               COLORS[method], f"{s.split('/')[-1]}: {e['ratio']:.2f}× copy")
    fig.suptitle(f"{method} on the winding set: test demos dashed, reproductions in colour")
    return save_figure(fig, Path(out_dir) / "figures" / "overview", dpi=90)["png"]


def write_html(results: dict, out_dir: Path) -> Path:
    """The page: the protocol, one row per shape (DTWD / copy of each method, the default's
    excursion, arrival, certificate and kept candidate), and the figures."""
    e, methods = html.escape, results["meta"]["methods"]
    head = ["shape", "copy DTWD (px)", *(f"{m}: DTWD ÷ copy" for m in methods), "default: excursion ÷ diag",
            "default: arrival ÷ duration", "certified (all)", "default's warp", "targets met (default)"]
    rows, figs = [], []
    for s, d in results["sets"].items():
        r, cells = d["methods"], [e(s), fmt(d["copy"], 0)]
        cells += [fmt(r[m]["ratio"]) if not r[m]["error"] else "failed" for m in methods]
        dflt = r.get("CDSP default", next(iter(r.values())))
        cells += [fmt(dflt["excursion"], 3), fmt(dflt["arrival_ratio"]),
                  fmt(all(v["certified"] for v in r.values())), e(str(dflt["kept"])), fmt(dflt["met"])]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        figs.append(f"<h3>{e(s)}</h3><figure><img src=\"{e(results['figures'][s])}\" alt=\"{e(s)}\" "
                    "style=\"max-width:100%\"></figure>")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>CDSP on the winding set</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto}}table{{border-collapse:collapse;font-size:90%}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style>
</head><body><h1>CDSP on the winding set (held-out, issue 36)</h1>
<p>{e(results['meta']['protocol'])}</p>
<p>Targets: DTWD ≤ {TARGET_RATIO:g}× copy; certified; excursion ≤ {TARGET_EXCURSION:g} of the training box's
diagonal; arrival (within 1 % of the diagonal of the goal) by {TARGET_ARRIVAL:g}× the demo's remaining duration.
Worst test demo per column, DTWD the mean over the 3 test demos. Mean DTWD ÷ copy over the shapes:
{'; '.join(f"{e(m)} {results['means'][m]:.2f}" for m in methods)}.{' Quick settings.' if results['meta']['quick'] else ''}</p>
<table><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>{''.join(rows)}</table>
{f'<figure><img src="{e(results["figures"]["overview"])}" alt="overview" style="max-width:100%"></figure>'
 if "overview" in results["figures"] else ""}
{''.join(figs)}
<p>Wall time {results['meta']['wall_s']:.0f} s.</p></body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path


def run(sets=SETS, methods=tuple(METHODS), *, quick: bool = False, out_dir=OUT, n_jobs: int = 1,
        force: bool = False) -> dict:
    out_dir, t0 = Path(out_dir), time.perf_counter()
    entries = parallel_map(run_job, [(s, m, quick, out_dir / "cache", force) for s in sets for m in methods],
                           n_jobs=n_jobs, label=job_label)
    per_set, figures, raw = {}, {}, {}
    for s in sets:
        mine = raw[s] = {e["method"]: e for e in entries if e["set"] == s}
        per_set[s] = {"copy": next((e["copy_mean"] for e in mine.values() if not e["error"]), None),
                      "methods": {m: dict({k: mine[m].get(k) for k in ("ratio", "dtwd_mean", "excursion", "arrival_ratio",
                                                                       "final_error", "certified", "fit_s", "kept",
                                                                       "warp_scores", "error", "tests")},
                                          met=met(mine[m])) for m in methods}}
        figures[s] = str(shape_figure(s, mine, out_dir).relative_to(out_dir))
    if "CDSP default" in methods:
        figures["overview"] = str(overview(raw, "CDSP default", out_dir).relative_to(out_dir))
    means = {m: float(np.mean([per_set[s]["methods"][m]["ratio"] for s in sets])) for m in methods}
    results = {"meta": {"protocol": PROTOCOL,
                        "sets": list(sets), "methods": list(methods), "quick": quick,
                        "settings": METHODS, "wall_s": time.perf_counter() - t0},
               "means": means, "sets": per_set, "figures": figures}
    write_json(out_dir / "results.json", results)
    return {"results": out_dir / "results.json", "html": write_html(results, out_dir)}


def main(argv=None):
    args = parser("python -m problems winding", "held-out accuracy on the synthesised winding set",
                  "two shapes, small fits (CI)", SETS, tuple(METHODS), OUT).parse_args(list(argv or []))
    sets = args.sets or (QUICK_SETS if args.quick else SETS)
    paths = run(sets, args.methods or tuple(METHODS), quick=args.quick, out_dir=args.out, n_jobs=args.jobs,
                force=args.force)
    res = json.loads(paths["results"].read_text())
    for s, d in res["sets"].items():
        print(f"{s:<18} copy {d['copy']:8.0f}  " + "  ".join(
            f"{m} {r['ratio']:.2f}" for m, r in d["methods"].items() if not r["error"]))
    print(f"winding: {paths['html']}")
    return 0

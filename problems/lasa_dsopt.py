"""CDSP under the LPV-DS (ds-opt) LASA protocol: 26 single-pattern shapes x CDSP variants.

The protocol (train on demos 1-4, test on 5-7, every 2nd sample, explicit-Euler reproduction
from the 20th point, DTWD) is :mod:`sosdyn.evaluation.dsopt`; this module only runs it per
(shape, variant, seed), caches one JSON per job in ``<out>/cache`` and writes
``<out>/results.json``, ``<out>/index.html`` and ``<out>/figures/lasa_dsopt.{png,svg}``
(``<out>`` = ``reports/lasa_dsopt`` by default).

``make lasa-dsopt`` runs all 26 shapes x every variant with one seed (``random_state=0``, ~15 min
on 2 cores). CDSP's EM is random; ``--seeds N`` repeats every fit with ``random_state =
0..N-1`` and reports mean +- std over the seeds (ds-opt averages 10 repetitions).
"""
from __future__ import annotations

import argparse
import html
import json
import math
import time
from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator

import sosdyn as sd
from sosdyn.errors import SosdynError
from sosdyn.evaluation import dsopt
from sosdyn.lfd.params import PLAIN, PRESETS
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import method_color, new_figure, styled

from . import lasa_corrective as corrective, lasa_warp as warp
from .cache import key_hash
from .jobs import add_scheduler_argument, parallel_map
from .jsonio import jsonable, write_json
from .settings import REPO, REPORTS

OUT = REPORTS / "lasa_dsopt"
SEDS_CSV = REPO.parent / "shared" / "reference" / "seds_lasa_published.csv"
CACHE_VERSION = 2

#: Variant name -> CDSP keyword arguments (random_state is set per seed).
VARIANTS = {
    "CDSP default": {}, "CDSP plain": PLAIN,           # CDSP(), and its core alone (no warp, no corrective refits)
    "CDSP paper": PRESETS["paper"],
    "CDSP-ICA": PRESETS["ica"],
    "CDSP-ICA g0.02": dict(PRESETS["ica"], gamma=0.02),
    "CDSP-ICA K10": dict(PRESETS["ica"], n_components=10),
    "CDSP-cubic-prox": PRESETS["cubic"], **corrective.VARIANTS, **warp.VARIANTS,
}
#: Selection variants: name -> the variants it chooses from, per shape, by the training demos'
#: reproduction DTWD (sosdyn.evaluation.dsopt.select_fit's rule, applied to the cached fits).
#: "CDSP selected": the three plain linear fits with the lowest 26-shape TRAINING mean (K = 10, K = 8,
#: gamma = 0.02: 1508, 1511, 1692 mm at random_state 0); "+cubic" adds the cubic preset (over the 10 s budget).
SELECTIONS = {"CDSP selected": ("CDSP plain", "CDSP-ICA K10", "CDSP-ICA g0.02"),
              **corrective.SELECTIONS, **warp.SELECTIONS,
              "CDSP selected+cubic": ("CDSP plain", "CDSP-ICA K10", "CDSP-ICA g0.02", "CDSP-cubic-prox")}
ALL_VARIANTS = tuple(VARIANTS) + tuple(SELECTIONS)
#: One line on the protocol for the report (its definition: sosdyn.evaluation.dsopt).
PROTOCOL = (f"ds-opt LASA protocol (sosdyn.evaluation.dsopt): train on demos "
            f"{', '.join(str(i + 1) for i in dsopt.TRAIN_DEMOS)}, test on "
            f"{', '.join(str(i + 1) for i in dsopt.TEST_DEMOS)}, every {dsopt.SAMPLE_STEP}nd sample; explicit "
            f"Euler (dt {dsopt.DT} s) from the {dsopt.START_INDEX + 1}th point; DTWD to the demonstration.")
QUICK = {"max_samples": 400, "max_iter": 4, "verify_samples": 2000}

#: 26-shape test-DTWD means (mm) as published for the ds-opt protocol (Figueroa & Billard,
#: "A Physically-Consistent Bayesian Non-Parametric Mixture Model for Dynamical System
#: Learning", CoRL 2018; quoted in sosdyn.evaluation.dsopt): LPV-DS with an EM GMM 1990, with
#: the PC-GMM 1749 and 1751, SEDS 3954. "copy" is measured, not published: the 26-shape mean
#: of dsopt.nearest_demo_score (notes/dsopt/baseline.md; recomputed as nearest_demo_mean).
REFERENCE = {"LPV-DS (EM GMM)": 1990.0, "LPV-DS PC-GMM": 1749.0, "LPV-DS PC-GMM (2)": 1751.0,
             "SEDS": 3954.0, "copy (nearest demo)": 660.0}


# ---------------------------------------------------------------- one job


def settings(variant: str, seed: int, quick: bool) -> dict:
    """The CDSP keyword arguments of ``variant`` with ``random_state = seed``."""
    out = dict(VARIANTS[variant], random_state=seed)   # selections: see select_job
    if quick:
        out.update(QUICK)
    return out


def cache_file(cache_dir: Path, shape: str, variant: str, seed: int, quick: bool) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in variant)
    return Path(cache_dir) / f"{shape}__{safe}__s{seed}{'__quick' if quick else ''}.json"


def run_job(shape: str, variant: str, seed: int, quick: bool, cache_dir: Path, force: bool) -> dict:
    """:func:`sosdyn.evaluation.dsopt.evaluate_shape` of one (shape, variant, seed), cached.

    A fit that raises a SosdynError (e.g. NotCertifiedError) gives an entry with ``error``
    and no scores; the cache key is the CDSP settings and the protocol version.
    """
    if variant in SELECTIONS:
        return select_job(shape, variant, seed, quick, cache_dir, force)
    kwargs = settings(variant, seed, quick)
    params = dict(corrective.key_params(kwargs), **warp.key_extra(kwargs))
    key = key_hash({"version": CACHE_VERSION, "shape": shape, "settings": params})
    path = cache_file(cache_dir, shape, variant, seed, quick)
    if not force:
        try:
            entry = json.loads(path.read_text())
            if entry.get("key_hash") == key:
                return dict(entry, from_cache=True)
        except (OSError, ValueError):
            pass
    fitted = []

    def fit(train):
        fitted.append(sd.CDSP(**kwargs).fit(train))
        return fitted[-1]

    entry = {"shape": shape, "variant": variant, "seed": seed, "key_hash": key, "error": None}
    try:
        entry.update(dsopt.evaluate_shape(fit, sd.load_lasa(shape)))
        entry["certified"] = bool(fitted[-1].certified_)
    except SosdynError as exc:
        entry.update(error=f"{type(exc).__name__}: {exc}", certified=False)
    entry = jsonable(entry)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")          # atomic: another worker never reads half a file
    tmp.write_text(json.dumps(entry, allow_nan=True))
    tmp.replace(path)
    return dict(entry, from_cache=False)


def select_job(shape: str, variant: str, seed: int, quick: bool, cache_dir: Path, force: bool) -> dict:
    """A selection variant: its candidates' entries (cached or fitted), and the one with the
    lowest training-reproduction DTWD (``dtwd_train_mean``: train demos only, the rule of
    :func:`sosdyn.evaluation.dsopt.select_fit`); fit time = the candidates' sum."""
    entries = {c: run_job(shape, c, seed, quick, cache_dir, force) for c in SELECTIONS[variant]}
    ok = {c: e for c, e in entries.items() if not e["error"]}
    if not ok:
        return dict(next(iter(entries.values())), variant=variant)
    best = min(ok, key=lambda c: ok[c]["dtwd_train_mean"])
    return dict(ok[best], variant=variant, selected=best, from_cache=all(e["from_cache"] for e in ok.values()),
                fit_s=sum(e["fit_s"] for e in ok.values()))


def job_label(entry: dict) -> str:
    head = f"{entry['shape']:<17} {entry['variant']:<13} seed {entry['seed']}"
    if entry["error"]:
        return f"{head} FAILED: {entry['error'][:120]}"
    src = "cache" if entry["from_cache"] else f"fit {entry['fit_s']:5.1f} s"
    return f"{head} test DTWD {entry['dtwd_test_mean']:8.1f}  ({src})"


# ---------------------------------------------------------------- aggregation


def _mean_std(values) -> tuple[float, float]:
    a = np.asarray(values, dtype=float)
    return float(a.mean()), float(a.std())


def shape_variant(entries: list[dict]) -> dict:
    """One (shape, variant) over its seeds: means, std over seeds of the test mean, flags."""
    ok = [e for e in entries if not e["error"]]
    out = {"n_seeds": len(entries), "n_ok": len(ok), "certified": bool(ok) and all(e["certified"] for e in ok),
           "errors": [e["error"] for e in entries if e["error"]]}
    if not ok:
        return dict(out, dtwd_test_mean=None, dtwd_test_std=None, dtwd_test=None, dtwd_train_mean=None,
                    ratio_to_nearest=None, fit_s=None)
    test_mean, test_std = _mean_std([e["dtwd_test_mean"] for e in ok])
    return dict(out, dtwd_test_mean=test_mean, dtwd_test_std=test_std,
                dtwd_test=np.mean([e["dtwd_test"] for e in ok], axis=0).tolist(),
                dtwd_train_mean=_mean_std([e["dtwd_train_mean"] for e in ok])[0],
                ratio_to_nearest=test_mean / ok[0]["nearest_demo"],
                fit_s=_mean_std([e["fit_s"] for e in ok])[0],
                n_points_test=[e["n_points_test"] for e in ok])


def summarize(per_shape: dict, variants, seds: dict | None) -> dict:
    """Per variant: 26-shape means (test, train), worst ratio to the nearest demo, counts."""
    out = {}
    for v in variants:
        rows = {s: d["variants"][v] for s, d in per_shape.items()}
        ok = {s: r for s, r in rows.items() if r["dtwd_test_mean"] is not None}
        summary = {"n_shapes": len(rows), "n_ok": len(ok),
                   "n_certified": sum(r["certified"] for r in rows.values())}
        if ok:
            worst = max(ok, key=lambda s: ok[s]["ratio_to_nearest"])
            summary.update(
                dtwd_test_mean=float(np.mean([r["dtwd_test_mean"] for r in ok.values()])),
                dtwd_test_median=float(np.median([r["dtwd_test_mean"] for r in ok.values()])),
                dtwd_train_mean=float(np.mean([r["dtwd_train_mean"] for r in ok.values()])),
                worst_ratio_to_nearest=ok[worst]["ratio_to_nearest"], worst_shape=worst,
                n_better_than_nearest=sum(r["ratio_to_nearest"] < 1 for r in ok.values()),
                fit_s_mean=float(np.mean([r["fit_s"] for r in ok.values()])))
            if seds:
                summary["n_better_than_seds"] = sum(
                    r["dtwd_test_mean"] < seds[s] for s, r in ok.items() if s in seds)
        out[v] = summary
    return out


def read_seds(path: Path = SEDS_CSV) -> dict | None:
    """``{shape: published SEDS test DTWD mean}``, or None (with a message) if the file is missing."""
    if not Path(path).is_file():
        print(f"lasa-dsopt: no published SEDS table at {path}; the SEDS column is left out. "
              "Try: place seds_lasa_published.csv there.")
        return None
    return {s: row["dtwd_test_mean"] for s, row in dsopt.load_seds_published(path).items()}


# ---------------------------------------------------------------- figure


def figure_caption(seeds: int, with_seds: bool) -> str:
    return ("Per-shape test DTWD (log scale) of the paper's CDSP, the default's plain fit, the default (its choice"
            " of diffeomorphic pre-warp) and the selection among corrective refits (every variant is in the table)"
            + (" (mean ± std over seeds)" if seeds > 1 else "") + ", the nearest training demo (open diamonds)"
            + (" and SEDS as published (crosses)" if with_seds else "")
            + f"; dashed: LPV-DS (PC-GMM) 26-shape mean {REFERENCE['LPV-DS PC-GMM']:.0f}, "
            + f"dotted: SEDS mean {REFERENCE['SEDS']:.0f}.")


#: The variants the figure draws when present (the per-shape table lists every variant).
FIGURE_VARIANTS = ("CDSP paper", "CDSP plain", "CDSP default", "CDSP corrective selected")
MARKERS = "os^v<>ph"


@styled
def figure(per_shape: dict, variants, seds: dict | None, out_dir: Path) -> dict:
    """Per-shape test DTWD on a log axis: a point per variant (+- std over seeds; the
    FIGURE_VARIANTS present, else the first len(MARKERS) run), the nearest demo and SEDS (published)
    as markers, the LPV-DS and SEDS 26-shape means as lines."""
    shapes = list(per_shape)
    variants = [v for v in FIGURE_VARIANTS if v in variants] or list(variants)[:len(MARKERS)]
    fig = new_figure(max(7.0, 0.42 * len(shapes) + 2), 4.2)
    ax = fig.add_subplot()
    x = np.arange(len(shapes))
    offsets = np.linspace(-0.22, 0.22, len(variants)) if len(variants) > 1 else [0.0]
    extra = [v for v in variants if v != "CDSP default"]
    colors = {v: method_color(v, extra) for v in extra}
    colors["CDSP default"] = "#0072B2"
    for v, dx, marker in zip(variants, offsets, MARKERS):
        y = np.array([per_shape[s]["variants"][v]["dtwd_test_mean"] or np.nan for s in shapes], dtype=float)
        err = np.array([per_shape[s]["variants"][v]["dtwd_test_std"] or 0.0 for s in shapes], dtype=float)
        ax.errorbar(x + dx, y, yerr=err if err.any() else None, fmt=marker, ms=4.5, color=colors[v],
                    label=v, capsize=2, lw=0.8)
    ax.plot(x, [per_shape[s]["nearest_demo"] for s in shapes], "D", ms=4, mfc="none",
            color="0.35", label="nearest training demo (copy)")
    if seds:
        ax.plot(x, [seds.get(s, np.nan) for s in shapes], "x", ms=5.5, color="black",
                label="SEDS (published)")
    for name, style, label in (("LPV-DS PC-GMM", "--", "LPV-DS"), ("SEDS", ":", "SEDS")):
        ax.axhline(REFERENCE[name], ls=style, color="0.3", lw=1)
        ax.text(1.005, REFERENCE[name], f"{label}\nmean {REFERENCE[name]:.0f}",
                transform=ax.get_yaxis_transform(), ha="left", va="center", fontsize=7.5, color="0.3")
    ax.set_yscale("log")
    ax.set_xticks(x, shapes, rotation=60, ha="right")
    ax.set_xlim(-0.6, len(shapes) - 0.4)
    ax.set_ylabel("test DTWD (mm, mean of demos 5-7)")
    ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: ""))
    handles, labels = ax.get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda i: labels[i] not in variants)   # variants first
    fig.legend([handles[i] for i in order], [labels[i] for i in order], loc="outside upper center",
               ncols=len(variants) + 2)
    ax.grid(axis="y", which="major", color="0.9", lw=0.6)
    return save_figure(fig, Path(out_dir) / "figures" / "lasa_dsopt", dpi=130)


# ---------------------------------------------------------------- report


def _fmt(value, digits=0) -> str:
    return "—" if value is None or not math.isfinite(value) else f"{value:,.{digits}f}"


def write_html(results: dict, out_dir: Path) -> Path:
    """A self-contained page: summary, per-shape table, figure (all text escaped)."""
    e = html.escape
    variants = results["meta"]["variants"]
    seeds = results["meta"]["seeds"]
    has_seds = results["meta"]["seds_source"] is not None
    rows = []
    for s, d in results["shapes"].items():
        cells = [e(s), _fmt(d["nearest_demo"])] + ([_fmt(d["seds_published"])] if has_seds else [])
        for v in variants:
            r = d["variants"][v]
            text = _fmt(r["dtwd_test_mean"]) + (f" ± {_fmt(r['dtwd_test_std'])}" if seeds > 1 and
                                                 r["dtwd_test_std"] is not None else "")
            cells.append(text + ("" if r["certified"] else " (not certified)"))
            cells.append(_fmt(r["ratio_to_nearest"], 2))
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = ["shape", "copy"] + (["SEDS (pub.)"] if has_seds else [])
    for v in variants:
        head += [e(v), "÷ copy"]
    summary = []
    for v, sm in results["summary"].items():
        summary.append(
            f"<li><b>{e(v)}</b>: {sm['n_shapes']}-shape test mean {_fmt(sm.get('dtwd_test_mean'))} "
            f"(median {_fmt(sm.get('dtwd_test_median'))}, train {_fmt(sm.get('dtwd_train_mean'))}); "
            f"worst ratio to copy {_fmt(sm.get('worst_ratio_to_nearest'), 2)} ({e(str(sm.get('worst_shape')))}); "
            f"better than copy on {sm.get('n_better_than_nearest')}/{sm['n_shapes']}"
            + (f", than SEDS on {sm['n_better_than_seds']}/{sm['n_shapes']}" if 'n_better_than_seds' in sm else "")
            + f"; certified {sm['n_certified']}/{sm['n_shapes']}; mean fit {_fmt(sm.get('fit_s_mean'), 1)} s</li>")
    refs = ", ".join(f"{e(k)} {v:.0f}" for k, v in results["reference"].items())
    fig = results["figures"]["lasa_dsopt"]
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>CDSP on the LPV-DS LASA protocol</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto}}table{{border-collapse:collapse;font-size:90%}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style></head>
<body><h1>CDSP on the LPV-DS (ds-opt) LASA protocol</h1>
<p>{e(results['meta']['protocol'])} Seeds per fit: {seeds} (random_state 0..{seeds - 1}).
Reference 26-shape means (mm; published, copy measured): {refs}.</p>
<ul>{''.join(summary)}</ul>
<figure><img src="{e(fig['png'])}" alt="per-shape test DTWD" style="max-width:100%">
<figcaption>{e(fig['caption'])}</figcaption></figure>
<table><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>{''.join(rows)}</table>
<p>Test DTWD in mm (mean over test demos 5-7); "÷ copy" = ratio to the nearest-training-demo score.
Wall time {results['meta']['wall_s']:.0f} s.</p></body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path


# ---------------------------------------------------------------- run


def run(shapes, variants=ALL_VARIANTS, *, seeds: int = 1, quick: bool = False, out_dir=OUT,
        n_jobs: int = 2, force: bool = False, seds_path: Path = SEDS_CSV) -> dict:
    """Fit and score every (shape, variant, seed), write results.json, the figure and index.html."""
    out_dir = Path(out_dir)
    t0 = time.perf_counter()
    cost = {"CDSP-cubic-prox": 0, **{v: 9 for v in SELECTIONS}}     # long jobs first, selections last
    items = sorted(((s, v, k, quick, out_dir / "cache", force) for s in shapes for v in variants
                    for k in range(seeds)), key=lambda i: cost.get(i[1], 3))
    entries = parallel_map(run_job, items, n_jobs=n_jobs, label=job_label)
    seds = read_seds(seds_path)
    per_shape = {}
    for s in shapes:
        mine = [e for e in entries if e["shape"] == s]
        nearest = next((e["nearest_demo"] for e in mine if not e["error"]), None)
        if nearest is None:
            train, test = dsopt.split(sd.load_lasa(s))
            nearest = dsopt.nearest_demo_score(train, test)
        per_shape[s] = {"nearest_demo": nearest, "seds_published": seds.get(s) if seds else None,
                        "variants": {v: shape_variant([e for e in mine if e["variant"] == v]) for v in variants}}
    results = {
        "meta": {"protocol": PROTOCOL,
                 "variants": list(variants),
                 "settings": {v: ({"select_from": SELECTIONS[v]} if v in SELECTIONS else settings(v, 0, quick))
                              for v in variants},
                 "seeds": seeds, "quick": quick, "shapes": list(shapes),
                 "seds_source": str(seds_path) if seds else None, "wall_s": time.perf_counter() - t0},
        "reference": REFERENCE,
        "nearest_demo_mean": float(np.mean([d["nearest_demo"] for d in per_shape.values()])),
        "seds_published_mean": (float(np.mean([d["seds_published"] for d in per_shape.values()]))
                                if seds and all(d["seds_published"] is not None for d in per_shape.values())
                                else None),
        "shapes": per_shape,
        "summary": summarize(per_shape, variants, seds),
    }
    paths = figure(per_shape, variants, seds, out_dir)
    results["figures"] = {"lasa_dsopt": {
        "png": "figures/lasa_dsopt.png", "svg": "figures/lasa_dsopt.svg",
        "caption": figure_caption(seeds, bool(seds))}}
    results["meta"]["wall_s"] = time.perf_counter() - t0
    write_json(out_dir / "results.json", results)
    return {"results": out_dir / "results.json", "html": write_html(results, out_dir), **paths}


def parse_args(argv) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m problems lasa-dsopt",
                                description="CDSP variants on the LPV-DS (ds-opt) LASA protocol")
    p.add_argument("--quick", action="store_true", help="quick CDSP settings (smaller fits)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--shapes", nargs="*", default=None, help="shapes (default: the 26 single-pattern ones)")
    p.add_argument("--variants", nargs="*", default=None, choices=ALL_VARIANTS,
                   help="CDSP variants (default: all)")
    p.add_argument("--seeds", type=int, default=1,
                   help="fits per (shape, variant), random_state 0..N-1 (default 1; ds-opt uses 10)")
    p.add_argument("--force", action="store_true", help="refit even when cached")
    add_scheduler_argument(p)                   # --scheduler ADDRESS: the jobs on a Dask cluster
    p.add_argument("--out", type=Path, default=OUT, help="output folder (default reports/lasa_dsopt)")
    args = p.parse_args(list(argv or []))
    if args.seeds < 1:
        p.error("--seeds must be >= 1")
    return args


def main(argv=None):
    args = parse_args(argv)
    t0 = time.perf_counter()
    paths = run(args.shapes or dsopt.SINGLE_PATTERN_SHAPES, args.variants or ALL_VARIANTS,
                seeds=args.seeds, quick=args.quick, out_dir=args.out, n_jobs=args.jobs, force=args.force)
    res = json.loads(paths["results"].read_text())
    for v, sm in res["summary"].items():
        print(f"{v:<13} test mean {_fmt(sm.get('dtwd_test_mean'))}  worst ratio to copy "
              f"{_fmt(sm.get('worst_ratio_to_nearest'), 2)} ({sm.get('worst_shape')})  ok {sm['n_ok']}/{sm['n_shapes']}")
    print(f"lasa-dsopt: {paths['html']} ({time.perf_counter() - t0:.1f} s)")
    return 0

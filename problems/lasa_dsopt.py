"""CDSP under the LPV-DS (ds-opt) LASA protocol: 26 single-pattern shapes x CDSP variants.

The protocol (train on demos 1-4, test on 5-7, every 2nd sample, explicit-Euler reproduction
from the 20th point, DTWD) is :mod:`sosdyn.evaluation.dsopt`; this module only runs it per
(shape, variant, seed), caches one JSON per job in ``<out>/cache`` and writes
``<out>/results.json``, ``<out>/index.html`` and ``<out>/figures/lasa_dsopt.{png,svg}``
(``<out>`` = ``reports/lasa_dsopt`` by default).

``make lasa-dsopt`` runs all 26 shapes x every variant with one seed (``random_state=0``, ~15 min
on 2 cores). CDSP's EM is random; ``--seeds N`` repeats every fit with ``random_state =
0..N-1`` and reports mean +- std over the seeds (ds-opt averages 10 repetitions). ``--split
swapped`` trains on demos 4-7 and tests on 1-3 (:data:`sosdyn.evaluation.dsopt.SPLITS`): a check
that choices made on one split hold on another; the split is in every cache key and in
results.json's meta.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import SosdynError
from sosdyn.evaluation import dsopt
from sosdyn.lfd.fit.params import PLAIN, PRESETS

from . import lasa_corrective as corrective
from . import lasa_warp as warp
from .cache import key_hash
from .jobs import add_scheduler_argument, parallel_map
from .jsonio import jsonable, write_json
from .lasa_dsopt_report import REFERENCE, figure, figure_caption, figure_variants, fmt, write_html
from .settings import REPO, REPORTS

OUT = REPORTS / "lasa_dsopt"
#: SEDS's published per-shape figures on this protocol (the ds-opt evaluation; dtwd_test_mean per shape).
SEDS_CSV = REPO / "problems" / "data" / "seds_lasa_published.csv"
CACHE_VERSION = 2

#: Variant name -> CDSP keyword arguments (random_state is set per seed).
VARIANTS = {
    "CDSP default": {}, "CDSP plain": PLAIN,           # CDSP(), and its core alone (no warp, no corrective refits)
    "CDSP posterior gating": {"gating": "posterior"},  # CDSP() with the gating it had before issue 34 (the posterior)
    "CDSP tempered gating": {"gating": "tempered"},
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
STANDARD = "standard"           # the protocol's split (dsopt.SPLITS)
QUICK = {"max_samples": 400, "max_iter": 4, "verify_samples": 2000}
#: Per-shape columns beyond DTWD (dsopt.reproduction_quality, worst test demo; mean over seeds).
QUALITY = ("arrival_ratio_test", "excursion_test", "final_error_test")


def protocol(split: str = STANDARD) -> str:
    """One line on the protocol with the split ``split`` for the report (its definition:
    sosdyn.evaluation.dsopt)."""
    train, test = dsopt.SPLITS[split]
    return (f"ds-opt LASA protocol (sosdyn.evaluation.dsopt), {split} split: train on demos "
            f"{', '.join(str(i + 1) for i in train)}, test on {', '.join(str(i + 1) for i in test)}, every "
            f"{dsopt.SAMPLE_STEP}nd sample; explicit Euler (dt {dsopt.DT} s) from the {dsopt.START_INDEX + 1}th "
            "point; DTWD to the demonstration.")


# ---------------------------------------------------------------- one job


def settings(variant: str, seed: int, quick: bool) -> dict:
    """The CDSP keyword arguments of ``variant`` with ``random_state = seed``."""
    out = dict(VARIANTS[variant], random_state=seed)   # selections: see select_job
    if quick:
        out.update(QUICK)
    return out


def cache_file(cache_dir: Path, shape: str, variant: str, seed: int, quick: bool, split: str = STANDARD) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in variant)
    tail = ("__quick" if quick else "") + ("" if split == STANDARD else f"__{split}")
    return Path(cache_dir) / f"{shape}__{safe}__s{seed}{tail}.json"


def job_key(shape: str, kwargs: dict, split: str) -> str:
    """The cache key: protocol version, shape, CDSP settings and, for a split other than the
    standard one, its demo indices (so the standard split's earlier entries stay valid)."""
    key = {"version": CACHE_VERSION, "shape": shape,
           "settings": warp.cdsp_key(kwargs)}
    if split != STANDARD:
        key["split"] = [list(i) for i in dsopt.SPLITS[split]]
    return key_hash(key)


def run_job(shape: str, variant: str, seed: int, quick: bool, cache_dir: Path, force: bool,
            split: str = STANDARD) -> dict:
    """:func:`sosdyn.evaluation.dsopt.evaluate_shape` of one (shape, variant, seed) on the split
    ``split`` (a name in dsopt.SPLITS), cached.

    A fit that raises a SosdynError (e.g. NotCertifiedError) gives an entry with ``error``
    and no scores; the cache key is :func:`job_key`.
    """
    if variant in SELECTIONS:
        return select_job(shape, variant, seed, quick, cache_dir, force, split)
    kwargs = settings(variant, seed, quick)
    key = job_key(shape, kwargs, split)
    path = cache_file(cache_dir, shape, variant, seed, quick, split)
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

    entry = {"shape": shape, "variant": variant, "seed": seed, "split": split, "key_hash": key, "error": None}
    try:
        entry.update(dsopt.evaluate_shape(fit, sd.load_lasa(shape), *dsopt.SPLITS[split]))
        entry["certified"] = bool(fitted[-1].certified_)
    except SosdynError as exc:
        entry.update(error=f"{type(exc).__name__}: {exc}", certified=False)
    entry = jsonable(entry)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")          # atomic: another worker never reads half a file
    tmp.write_text(json.dumps(entry, allow_nan=True))
    tmp.replace(path)
    return dict(entry, from_cache=False)


def select_job(shape: str, variant: str, seed: int, quick: bool, cache_dir: Path, force: bool,
               split: str = STANDARD) -> dict:
    """A selection variant: its candidates' entries (cached or fitted), and the one with the
    lowest training-reproduction DTWD (``dtwd_train_mean``: train demos only, the rule of
    :func:`sosdyn.evaluation.dsopt.select_fit`); fit time = the candidates' sum."""
    entries = {c: run_job(shape, c, seed, quick, cache_dir, force, split) for c in SELECTIONS[variant]}
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
                    ratio_to_nearest=None, fit_s=None, **dict.fromkeys(QUALITY))
    test_mean, test_std = _mean_std([e["dtwd_test_mean"] for e in ok])
    out.update({k: (_mean_std([e[k] for e in ok])[0] if all(k in e for e in ok) else None)   # None: cached
                for k in QUALITY})                                                          # before the column
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
                fit_s_mean=float(np.mean([r["fit_s"] for r in ok.values()])),
                **{f"worst_{k}": (max(r[k] for r in ok.values()) if all(r[k] is not None for r in ok.values())
                                  else None) for k in QUALITY})
            if seds:
                summary["n_better_than_seds"] = sum(
                    r["dtwd_test_mean"] < seds[s] for s, r in ok.items() if s in seds)
        out[v] = summary
    return out


def _shown(path) -> str:
    """``path`` relative to the repository when inside it (results.json does not name this machine)."""
    path = Path(path).resolve()
    return str(path.relative_to(REPO.resolve())) if path.is_relative_to(REPO.resolve()) else str(path)


def read_seds(path: Path = SEDS_CSV) -> dict | None:
    """``{shape: published SEDS test DTWD mean}``, or None (with a message) if the file is missing."""
    if not Path(path).is_file():
        print(f"lasa-dsopt: no published SEDS table at {path}; the SEDS column is left out. "
              "Try: place seds_lasa_published.csv there.")
        return None
    return {s: row["dtwd_test_mean"] for s, row in dsopt.load_seds_published(path).items()}



# ---------------------------------------------------------------- run


def run(shapes, variants=ALL_VARIANTS, *, seeds: int = 1, quick: bool = False, out_dir=OUT,
        n_jobs: int = 2, force: bool = False, seds_path: Path = SEDS_CSV, split: str = STANDARD) -> dict:
    """Fit and score every (shape, variant, seed) on the split ``split`` (dsopt.SPLITS), write
    results.json, the figure and index.html."""
    out_dir = Path(out_dir)
    t0 = time.perf_counter()
    cost = {"CDSP-cubic-prox": 0, **{v: 9 for v in SELECTIONS}}     # long jobs first, selections last
    items = sorted(((s, v, k, quick, out_dir / "cache", force, split) for s in shapes for v in variants
                    for k in range(seeds)), key=lambda i: cost.get(i[1], 3))
    entries = parallel_map(run_job, items, n_jobs=n_jobs, label=job_label)
    seds = read_seds(seds_path) if split == STANDARD else None      # published for the standard split only
    per_shape = {}
    for s in shapes:
        mine = [e for e in entries if e["shape"] == s]
        nearest = next((e["nearest_demo"] for e in mine if not e["error"]), None)
        if nearest is None:
            train, test = dsopt.split(sd.load_lasa(s), *dsopt.SPLITS[split])
            nearest = dsopt.nearest_demo_score(train, test)
        per_shape[s] = {"nearest_demo": nearest, "seds_published": seds.get(s) if seds else None,
                        "variants": {v: shape_variant([e for e in mine if e["variant"] == v]) for v in variants}}
    results = {
        "meta": {"protocol": protocol(split), "split": split, "split_demos": dsopt.SPLITS[split],
                 "variants": list(variants),
                 "settings": {v: ({"select_from": SELECTIONS[v]} if v in SELECTIONS else settings(v, 0, quick))
                              for v in variants},
                 "seeds": seeds, "quick": quick, "shapes": list(shapes),
                 "seds_source": _shown(seds_path) if seds else None, "wall_s": time.perf_counter() - t0},
        "reference": REFERENCE if split == STANDARD else {},     # published for the standard split only
        "nearest_demo_mean": float(np.mean([d["nearest_demo"] for d in per_shape.values()])),
        "seds_published_mean": (float(np.mean([d["seds_published"] for d in per_shape.values()]))
                                if seds and all(d["seds_published"] is not None for d in per_shape.values())
                                else None),
        "shapes": per_shape,
        "summary": summarize(per_shape, variants, seds),
    }
    paths = figure(per_shape, variants, seds, out_dir, dsopt.SPLITS[split][1], references=split == STANDARD)
    results["figures"] = {"lasa_dsopt": {
        "png": "figures/lasa_dsopt.png", "svg": "figures/lasa_dsopt.svg",
        "caption": figure_caption(seeds, bool(seds), references=split == STANDARD,
                                  drawn=figure_variants(variants))}}
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
    p.add_argument("--split", choices=tuple(dsopt.SPLITS), default=STANDARD,
                   help="standard: train demos 1-4, test 5-7 (the protocol); swapped: train 4-7, test 1-3")
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
                seeds=args.seeds, quick=args.quick, out_dir=args.out, n_jobs=args.jobs, force=args.force,
                split=args.split)
    res = json.loads(paths["results"].read_text())
    for v, sm in res["summary"].items():
        print(f"{v:<13} test mean {fmt(sm.get('dtwd_test_mean'))}  worst ratio to copy "
              f"{fmt(sm.get('worst_ratio_to_nearest'), 2)} ({sm.get('worst_shape')})  ok {sm['n_ok']}/{sm['n_shapes']}")
    print(f"lasa-dsopt: {paths['html']} ({time.perf_counter() - t0:.1f} s)")
    return 0

"""The report of problems.lasa_dsopt: the per-shape figure and the HTML page (results.json in, files out).

The published reference means live here (:data:`REFERENCE`); the experiment itself (fits, cache,
aggregation) is :mod:`problems.lasa_dsopt`.
"""
from __future__ import annotations

import html
import json
import math
from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator

from sosdyn.errors import InputError
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import method_color, new_figure, styled
from sosdyn.report.html import report_css

from .settings import REPORTS

#: 26-shape test-DTWD means (mm) as published for the ds-opt protocol (Figueroa & Billard,
#: "A Physically-Consistent Bayesian Non-Parametric Mixture Model for Dynamical System
#: Learning", CoRL 2018; quoted in sosdyn.evaluation.dsopt): LPV-DS with an EM GMM 1990, with
#: the PC-GMM 1749 and 1751, SEDS 3954. "copy" is measured, not published: the 26-shape mean
#: of dsopt.nearest_demo_score (recomputed in every run as nearest_demo_mean).
REFERENCE = {"LPV-DS (EM GMM)": 1990.0, "LPV-DS PC-GMM": 1749.0, "LPV-DS PC-GMM (2)": 1751.0,
             "SEDS": 3954.0, "copy (nearest demo)": 660.0}


# ---------------------------------------------------------------- figure


def demo_names(indices) -> str:
    """Demonstration numbers as the protocol names them (1-based): (4, 5, 6) -> "5-7"."""
    return f"{indices[0] + 1}-{indices[-1] + 1}"


#: The variants the figure draws when present (the per-shape table lists every variant).
FIGURE_VARIANTS = ("CDSP paper", "CDSP plain", "CDSP default", "CDSP corrective selected")
MARKERS = "os^v<>ph"


def figure_variants(variants) -> list:
    """The variants the figure draws: all of a small run (<= 4), else the FIGURE_VARIANTS present (else
    the first len(MARKERS) run)."""
    variants = list(variants)
    if len(variants) <= 4:
        return variants
    return [v for v in FIGURE_VARIANTS if v in variants] or variants[:len(MARKERS)]


def figure_caption(seeds: int, with_seds: bool, references: bool = True, drawn=FIGURE_VARIANTS) -> str:
    what = ("the paper's CDSP, the default's plain fit, the default (its choice of diffeomorphic pre-warp) and "
            "the selection among corrective refits" if tuple(drawn) == FIGURE_VARIANTS else ", ".join(drawn))
    return (f"Per-shape test DTWD (log scale) of {what} (every variant is in the table)"
            + (" (mean ± std over seeds)" if seeds > 1 else "") + ", the nearest training demo (open diamonds)"
            + (" and SEDS as published (crosses)" if with_seds else "")
            + (f"; dashed: LPV-DS (PC-GMM) 26-shape mean {REFERENCE['LPV-DS PC-GMM']:.0f}, "
               f"dotted: SEDS mean {REFERENCE['SEDS']:.0f}." if references else
               "; no published references: they are for the standard split."))




@styled
def figure(per_shape: dict, variants, seds: dict | None, out_dir: Path, test_demos=(4, 5, 6),
           references: bool = True) -> dict:
    """Per-shape test DTWD on a log axis: a point per variant (+- std over seeds; the
    FIGURE_VARIANTS present, else the first len(MARKERS) run), the nearest demo and SEDS (published)
    as markers, the LPV-DS and SEDS 26-shape means as lines (``references``: published for the
    standard split only)."""
    shapes = list(per_shape)
    variants = figure_variants(variants)
    fig = new_figure(max(7.0, 0.42 * len(shapes) + 2), 4.2)
    ax = fig.add_subplot()
    x = np.arange(len(shapes))
    offsets = np.linspace(-0.22, 0.22, len(variants)) if len(variants) > 1 else [0.0]
    extra = [v for v in variants if v != "CDSP default"]
    colors = {v: method_color(v, extra) for v in extra}
    colors["CDSP default"] = method_color("CDSP")
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
    for name, style, label in (("LPV-DS PC-GMM", "--", "LPV-DS"), ("SEDS", ":", "SEDS")) if references else ():
        ax.axhline(REFERENCE[name], ls=style, color="0.3", lw=1)
        ax.text(1.005, REFERENCE[name], f"{label}\nmean {REFERENCE[name]:.0f}",
                transform=ax.get_yaxis_transform(), ha="left", va="center", fontsize=7.5, color="0.3")
    ax.set_yscale("log")
    ax.set_xticks(x, shapes, rotation=60, ha="right")
    ax.set_xlim(-0.6, len(shapes) - 0.4)
    ax.set_ylabel(f"test DTWD (mm, mean of demos {demo_names(test_demos)})")
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


def fmt(value, digits=0) -> str:
    return "—" if value is None or not math.isfinite(value) else f"{value:,.{digits}f}"


#: At most this many columns in a table of the page (its tables fit a laptop window).
MAX_COLUMNS = 10


def _table(head, rows, sticky=False) -> str:
    """An HTML table in the report's style (cells already escaped); the first column is the key."""
    cell = lambda tag, i, c: f'<{tag}{" class=key" if i == 0 else ""}>{c}</{tag}>'   # noqa: E731
    body = "".join("<tr>" + "".join(cell("td", i, c) for i, c in enumerate(r)) + "</tr>" for r in rows)
    return (f'<div class="table-wrap{" sticky" if sticky else ""}"><table><thead><tr>'
            + "".join(cell("th", i, h) for i, h in enumerate(head)) + f"</tr></thead><tbody>{body}</tbody></table></div>")


def _dtwd_cell(r: dict, seeds: int) -> str:
    """Test DTWD (± std over seeds), marked when not certified."""
    text = fmt(r["dtwd_test_mean"]) + (f" ± {fmt(r['dtwd_test_std'])}" if seeds > 1 and
                                       r["dtwd_test_std"] is not None else "")
    return text + ("" if r["certified"] else ' <span class="fail">(not certified)</span>')


def summary_table(results: dict) -> str:
    """One row per variant: 26-shape means, worst ratio to the copy, counts, fit time."""
    e, has_seds = html.escape, results["meta"]["seds_source"] is not None
    head = ["variant", "test mean", "test median", "train mean", "worst ÷ copy (shape)",
            "better than copy"] + (["better than SEDS"] if has_seds else []) + ["certified", "mean fit (s)"]
    rows = []
    for v, sm in results["summary"].items():
        n = sm["n_shapes"]
        rows.append([e(v), fmt(sm.get("dtwd_test_mean")), fmt(sm.get("dtwd_test_median")),
                     fmt(sm.get("dtwd_train_mean")),
                     f"{fmt(sm.get('worst_ratio_to_nearest'), 2)} ({e(str(sm.get('worst_shape')))})",
                     f"{sm.get('n_better_than_nearest', 0)}/{n}"]
                    + ([f"{sm.get('n_better_than_seds', 0)}/{n}"] if has_seds else [])
                    + [f"{sm['n_certified']}/{n}", fmt(sm.get("fit_s_mean"), 1)])
    return _table(head, rows)


def quality_table(results: dict) -> str:
    """One row per variant: the worst shape's arrival ratio, excursion and final error (each the
    worst test demo of a shape, as on the real-data page; absent for entries fitted before them)."""
    e = html.escape
    head = ["variant", "worst arrival ÷ duration", "worst excursion ÷ diag", "worst final error ÷ diag"]
    q = lambda value, digits: "∞ (never arrives)" if value == math.inf else fmt(value, digits)   # noqa: E731
    rows = [[e(v), q(sm.get("worst_arrival_ratio_test"), 2), q(sm.get("worst_excursion_test"), 3),
             q(sm.get("worst_final_error_test"), 4)] for v, sm in results["summary"].items()]
    return _table(head, rows)


def shape_table(results: dict, variants) -> str:
    """One row per shape: the copy, SEDS (published) and the drawn variants' test DTWD (÷ copy)."""
    e, has_seds, seeds = html.escape, results["meta"]["seds_source"] is not None, results["meta"]["seeds"]
    head = ["shape", "copy"] + (["SEDS (pub.)"] if has_seds else []) + [e(v) for v in variants]
    rows = [[e(s), fmt(d["nearest_demo"])] + ([fmt(d["seds_published"])] if has_seds else [])
            + [f"{_dtwd_cell(d['variants'][v], seeds)} <span class=note>×{fmt(d['variants'][v]['ratio_to_nearest'], 2)}</span>"
               for v in variants] for s, d in results["shapes"].items()]
    return _table(head, rows, sticky=True)


def variant_details(results: dict) -> str:
    """Per variant, a folded table: shape, test and train DTWD, ratio to the copy, fit time."""
    e, seeds = html.escape, results["meta"]["seeds"]
    out = []
    for v in results["meta"]["variants"]:
        rows = [[e(s), _dtwd_cell(d["variants"][v], seeds), fmt(d["variants"][v].get("dtwd_train_mean")),
                 fmt(d["variants"][v]["ratio_to_nearest"], 2), fmt(d["variants"][v].get("arrival_ratio_test"), 2),
                 fmt(d["variants"][v].get("excursion_test"), 3), fmt(d["variants"][v].get("final_error_test"), 4),
                 fmt(d["variants"][v].get("fit_s"), 1)]
                for s, d in results["shapes"].items()]
        settings = results["meta"].get("settings", {}).get(v)
        out.append(f"<details><summary>{e(v)}</summary>"
                   + (f'<p class="note">settings: <code>{e(str(settings))}</code></p>' if settings else "")
                   + _table(["shape", "test DTWD", "train DTWD", "÷ copy", "arrival ÷ duration",
                                                       "excursion ÷ diag", "final error ÷ diag", "fit (s)"], rows) + "</details>")
    return "".join(out)


def write_html(results: dict, out_dir: Path) -> Path:
    """A self-contained page in the user report's style (:func:`sosdyn.report.html.report_css`):
    summary table, figure, per-shape table of the drawn variants, per-variant details (all text
    escaped; no table wider than :data:`MAX_COLUMNS`)."""
    e = html.escape
    seeds = results["meta"]["seeds"]
    refs = ", ".join(f"{e(k)} {v:.0f}" for k, v in results["reference"].items())
    refs = (f"Reference 26-shape means (mm; published, copy measured): {refs}." if refs else
            f"Copy (nearest training demo) mean {fmt(results['nearest_demo_mean'])} mm; no published references "
            "(they are for the standard split).")
    test_demos = demo_names(results["meta"].get("split_demos", [None, (4, 5, 6)])[1])
    fig = results["figures"]["lasa_dsopt"]
    drawn = figure_variants(results["meta"]["variants"])
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>CDSP on the LPV-DS LASA protocol</title>
<style>
{report_css()}</style></head>
<body><header><h1>CDSP on the LPV-DS (ds-opt) LASA protocol</h1>
<p class="subtitle">{e(results['meta']['protocol'])} Seeds per fit: {seeds} (random_state 0..{seeds - 1}).
{refs} Wall time {results['meta']['wall_s']:.0f} s.</p></header>
<h2>Summary</h2>
<p class="note">Test DTWD in mm, mean over test demos {test_demos}, per variant over the {len(results['shapes'])} shapes;
"÷ copy" = ratio to the nearest-training-demo score.</p>
{summary_table(results)}
<p class="note">Reproduction quality, as on the real-data page (sosdyn.evaluation.dsopt.reproduction_quality):
arrival = first time within 1 % of the training box's diagonal of the goal over the test demo's remaining duration;
excursion = farthest point outside the training box over its diagonal; final error = distance from the
reproduction's end to the test demo's end over the diagonal. Worst test demo per shape, then worst shape
(per-shape values under the per-variant details).</p>
{quality_table(results)}
<h2>Per shape</h2>
<figure><img src="{e(fig['png'])}" alt="per-shape test DTWD"><figcaption>{e(fig['caption'])}</figcaption></figure>
<p class="note">Test DTWD (mm) of the variants drawn in the figure; small: ratio to the copy.
Every variant, shape by shape, is under <a href="#details">Per-variant details</a>.</p>
{shape_table(results, drawn)}
<h2 id="details">Per-variant details</h2>
{variant_details(results)}
</body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path


def rebuild(out_dir: Path) -> dict:
    """Redraw the figure and rewrite index.html of a finished run from its ``results.json``
    (no fitting): ``python -m problems lasa-dsopt-report reports/lasa_dsopt ...``."""
    out_dir = Path(out_dir)
    results = json.loads((out_dir / "results.json").read_text())
    per_shape, meta = results["shapes"], results["meta"]
    seds = ({s: d["seds_published"] for s, d in per_shape.items() if d.get("seds_published") is not None}
            if meta.get("seds_source") else None)
    test_demos = meta.get("split_demos", [None, (4, 5, 6)])[1]
    paths = figure(per_shape, meta["variants"], seds, out_dir, test_demos, references=bool(results["reference"]))
    return {"html": write_html(results, out_dir), **paths}


def main(argv=None) -> int:
    """``python -m problems lasa-dsopt-report [DIR ...]``: :func:`rebuild` each folder (default
    every ``reports/lasa_dsopt*`` with a results.json)."""
    folders = [Path(a) for a in argv or []] or sorted(p.parent for p in REPORTS.glob("lasa_dsopt*/results.json"))
    for folder in folders:
        if not (folder / "results.json").is_file():
            raise InputError(f"{folder} has no results.json. Try: a folder written by python -m problems lasa-dsopt.")
        print(f"lasa-dsopt-report: {rebuild(folder)['html']}")
    return 0

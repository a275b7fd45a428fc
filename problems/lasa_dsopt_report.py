"""The report of problems.lasa_dsopt: the per-shape figure and the HTML page (results.json in, files out).

The published reference means live here (:data:`REFERENCE`); the experiment itself (fits, cache,
aggregation) is :mod:`problems.lasa_dsopt`.
"""
from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator

from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import method_color, new_figure, styled

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


def write_html(results: dict, out_dir: Path) -> Path:
    """A self-contained page: summary, per-shape table, figure (all text escaped)."""
    e = html.escape
    variants = results["meta"]["variants"]
    seeds = results["meta"]["seeds"]
    has_seds = results["meta"]["seds_source"] is not None
    rows = []
    for s, d in results["shapes"].items():
        cells = [e(s), fmt(d["nearest_demo"])] + ([fmt(d["seds_published"])] if has_seds else [])
        for v in variants:
            r = d["variants"][v]
            text = fmt(r["dtwd_test_mean"]) + (f" ± {fmt(r['dtwd_test_std'])}" if seeds > 1 and
                                                 r["dtwd_test_std"] is not None else "")
            cells.append(text + ("" if r["certified"] else " (not certified)"))
            cells.append(fmt(r["ratio_to_nearest"], 2))
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = ["shape", "copy"] + (["SEDS (pub.)"] if has_seds else [])
    for v in variants:
        head += [e(v), "÷ copy"]
    summary = []
    for v, sm in results["summary"].items():
        summary.append(
            f"<li><b>{e(v)}</b>: {sm['n_shapes']}-shape test mean {fmt(sm.get('dtwd_test_mean'))} "
            f"(median {fmt(sm.get('dtwd_test_median'))}, train {fmt(sm.get('dtwd_train_mean'))}); "
            f"worst ratio to copy {fmt(sm.get('worst_ratio_to_nearest'), 2)} ({e(str(sm.get('worst_shape')))}); "
            f"better than copy on {sm.get('n_better_than_nearest')}/{sm['n_shapes']}"
            + (f", than SEDS on {sm['n_better_than_seds']}/{sm['n_shapes']}" if 'n_better_than_seds' in sm else "")
            + f"; certified {sm['n_certified']}/{sm['n_shapes']}; mean fit {fmt(sm.get('fit_s_mean'), 1)} s</li>")
    refs = ", ".join(f"{e(k)} {v:.0f}" for k, v in results["reference"].items())
    refs = (f"Reference 26-shape means (mm; published, copy measured): {refs}." if refs else
            f"Copy (nearest training demo) mean {fmt(results['nearest_demo_mean'])} mm; no published references "
            "(they are for the standard split).")
    test_demos = demo_names(results["meta"].get("split_demos", [None, (4, 5, 6)])[1])
    fig = results["figures"]["lasa_dsopt"]
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>CDSP on the LPV-DS LASA protocol</title>
<style>body{{font-family:sans-serif;max-width:1100px;margin:2em auto}}table{{border-collapse:collapse;font-size:90%}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child{{text-align:left}}</style></head>
<body><h1>CDSP on the LPV-DS (ds-opt) LASA protocol</h1>
<p>{e(results['meta']['protocol'])} Seeds per fit: {seeds} (random_state 0..{seeds - 1}).
{refs}</p>
<ul>{''.join(summary)}</ul>
<figure><img src="{e(fig['png'])}" alt="per-shape test DTWD" style="max-width:100%">
<figcaption>{e(fig['caption'])}</figcaption></figure>
<table><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>{''.join(rows)}</table>
<p>Test DTWD in mm (mean over test demos {test_demos}); "÷ copy" = ratio to the nearest-training-demo score.
Wall time {results['meta']['wall_s']:.0f} s.</p></body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path

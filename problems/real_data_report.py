"""The report of problems.real_data: one figure per set and the HTML page (results.json in, files out)."""
from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from sosdyn.evaluation.realdata import split_first
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import method_color, new_figure, styled

from .real_data_blocks import TARGETS

COLORS = {"CDSP default": "#0072B2", "CDSP plain": "#E69F00"}
VIEW_PAD = 0.3          # the axes show the data's box widened by this fraction on each side (paths leaving it are cut)


def _color(method: str, methods) -> str:
    return COLORS.get(method) or method_color(method, [m for m in methods if m not in COLORS])


@styled
def figure(name: str, demos, paths: dict, out_dir: Path) -> dict:
    """Training demos (grey), test demos (black, dashed) and each method's reproductions from
    the test starts: a 3-D view and the x-y and x-z projections for a 3-D set, one panel in 2-D."""
    train, test = split_first(demos)
    dim = demos.dim
    views = [(0, 1, 2), (0, 1), (0, 2)] if dim >= 3 else [(0, 1)]
    fig = new_figure(4.8 * len(views), 4.2)
    labels = "xyz"
    pos = np.vstack([d.pos for d in demos])
    pad = VIEW_PAD * (pos.max(axis=0) - pos.min(axis=0))
    lo, hi = pos.min(axis=0) - pad, pos.max(axis=0) + pad
    for k, axes in enumerate(views):
        ax = fig.add_subplot(1, len(views), k + 1, **({"projection": "3d"} if len(axes) == 3 else {}))

        def draw(points, **style):
            p = np.array(points, dtype=float)
            p[np.any((p < lo) | (p > hi), axis=1)] = np.nan        # 3-D axes do not clip
            ax.plot(*(p[:, a] for a in axes), **style)

        for i, d in enumerate(train):
            draw(d.pos, color="0.75", lw=0.7, label="training demos" if i == 0 else None)
        for i, d in enumerate(test):
            draw(d.pos, color="black", lw=0.9, ls="--", label="test demos" if i == 0 else None)
        for m, reps in paths.items():
            same = next((o for o in paths if o != m and list(paths).index(o) < list(paths).index(m)
                         and reps and paths[o] == reps), None)
            style = {"ls": (0, (4, 3)), "lw": 1.6} if same else {"lw": 1.0}
            label = f"{m} (= {same}: the same fit chosen)" if same else m
            for i, p in enumerate(reps or []):
                draw(p, color=_color(m, list(paths)), alpha=0.85, label=label if i == 0 else None, **style)
        goal = train.goal
        ax.plot(*([goal[a]] for a in axes), marker="*", ms=10, color="black", ls="none")
        ax.set_xlabel(f"{labels[axes[0]]} ({demos.units})")
        ax.set_ylabel(f"{labels[axes[1]]} ({demos.units})")
        ax.set_xlim(lo[axes[0]], hi[axes[0]])
        ax.set_ylim(lo[axes[1]], hi[axes[1]])
        if len(axes) == 3:
            ax.set_zlim(lo[axes[2]], hi[axes[2]])
            ax.set_zlabel(f"{labels[axes[2]]} ({demos.units})")
    handles, names = fig.axes[-1].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncols=len(names))
    fig.suptitle(f"{name}: {len(train)} training, {len(test)} test demos; reproductions from the test starts "
                 f"(axes: the data's box + {VIEW_PAD:.0%})")
    return save_figure(fig, Path(out_dir) / "figures" / name.replace("/", "__"), dpi=110)


def fmt(value, digits=2) -> str:
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "NO"
    return "∞" if not math.isfinite(value) else f"{value:,.{digits}f}"


def met_cell(t: dict) -> str:
    """The targets cell: "all", the missed ones, or for a method without a certificate the others' verdict."""
    missed = [k for k, v in t.items() if k != "all" and v is False]
    if t["all"]:
        return "all"
    return ("missed: " + ", ".join(missed)) if missed else "the others met (no certificate)"


def blocks_html(found: dict | None) -> str:
    """The section "What blocks each missed target" from :func:`problems.real_data_blocks.blocks`."""
    if not found:
        return ""
    e, items = html.escape, []
    for s, d in found["numbers"].items():
        parts = []
        if d["ratio"] > TARGETS["ratio"] or (d["dmp_ratio"] is not None and d["ratio"] > d["dmp_ratio"]):
            parts.append(f"DTWD {d['ratio']:.2f}× copy (DMP {fmt(d['dmp_ratio'])}×); copying the training demo with "
                         f"the nearest start scores {d['start_copy_ratio']:.2f}×, two training demos differ by "
                         f"{d['spread_ratio']:.2f}× on average")
        if max(d["excursion_beyond_start"]) > TARGETS["excursion_beyond_start"]:
            parts.append(f"excursion beyond the start {max(d['excursion_beyond_start']):.3f} (outside the training box "
                         f"{max(d['excursion']):.3f}; the test starts themselves lie up to "
                         f"{max(d['start_excursion']):.3f} outside it; certified bound "
                         f"{fmt(max((b for b in d['excursion_bound'] if b is not None), default=None), 3)})")
        if parts and d.get("rise"):
            parts.append(f"the training demos' metric distance to the goal rises by up to {max(d['rise']):.2f}× "
                         f"(the certificate forbids any rise: blocks_metric); they cross {d['crossings']} times "
                         "(a first-order field follows one path per state)")
        if d["arrival_ratio"] > TARGETS["arrival_ratio"]:
            parts.append(f"arrival {d['arrival_ratio']:.2f}× the duration: {d['cut_moving']} of {len(d['end_speed'])} "
                         "demos end at more than 10 % of their peak speed (cut while moving)")
        if parts:
            items.append(f"<li><b>{e(s)}</b>: {e('; '.join(parts))}.</li>")
    figs = "".join(f"<figure><img src=\"{e(p)}\" alt=\"{e(k)}\" style=\"max-width:100%\"><figcaption>{e(k)} "
                   f"({e(p)})</figcaption></figure>" for k, p in found["figures"].items())
    return (f"<h2>What blocks each missed target</h2><p>Numbers for CDSP default; the module "
            f"problems.real_data_blocks says how each is computed.</p><ul>{''.join(items)}</ul>{figs}")


def write_html(results: dict, out_dir: Path) -> Path:
    """The page: protocol, one table row per (set, method) with issue 36's targets, figures."""
    e = html.escape
    head = ["set", "method", "test DTWD ÷ copy", "excursion ÷ diag", "start excursion", "excursion beyond the start",
            "certified excursion bound", "arrival ÷ duration (worst)", "arrived within 2×", "final error ÷ diag",
            "certified", "fit s", "targets met"]
    rows, figs = [], []
    for s, d in results["sets"].items():
        for m, r in d["methods"].items():
            if r["error"] or r["failure"]:
                cells = [e(s), e(m), f"failed: {e(str(r['error'] or r['failure'])[:160])}"] + [""] * (len(head) - 3)
            else:
                t = r["targets"]
                cells = [e(s), e(m), fmt(r["ratio"]), fmt(r["excursion"], 3),
                         fmt(r.get("start_excursion"), 3), fmt(r.get("excursion_beyond_start"), 3),
                         fmt(r.get("excursion_bound"), 3), fmt(r["arrival_ratio"]),
                         f"{r['arrived'][0]} of {r['arrived'][1]}",
                         fmt(r["final_error"], 3), "—" if r["certified"] is None else fmt(r["certified"]),
                         fmt(r["fit_s"], 1), met_cell(t)]
            rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
        pre = next(iter(d["methods"].values()))["preprocess"] or []
        fig = results["figures"][s]
        figs.append(f"<h3>{e(s)}</h3><p>{d['n_demos']} demonstrations, {d['dim']}-D, units {e(d['units'])}. "
                    f"Preprocessing (training demos): {e('; '.join(pre))}.</p>"
                    f"<figure><img src=\"{e(fig['png'])}\" alt=\"{e(s)}\" style=\"max-width:100%\"></figure>")
    na = "; ".join(f"{e(k)}: {e(v)}" for k, v in results["meta"]["not_applicable"].items())
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>CDSP on real demonstrations</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto}}table{{border-collapse:collapse;font-size:90%}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child,td:nth-child(2){{text-align:left}}</style>
</head><body><h1>CDSP on real demonstrations (held-out)</h1>
<p>{e(results['meta']['protocol'])} Full protocol: sosdyn.evaluation.realdata. Positions only (x, y, z) for
the pose sets; hammer has no time stamps and is read at a declared 0.01 s per sample; robottasks positions
are in cm (inferred). Not evaluated: {na}.{' Quick settings.' if results['meta']['quick'] else ''}</p>
<p>Targets (issue 36): test DTWD ≤ {TARGETS['ratio']:g}× copy and no worse than DMP's; excursion beyond the
training box widened to hold the start ≤ {TARGETS['excursion_beyond_start']:g} of the training box's diagonal;
arrival (within 1 % of the diagonal of the goal) by {TARGETS['arrival_ratio']:g}× the demo's remaining duration
(every test demo); certified. Each column is the worst test demo, except DTWD (mean over test demos) and the
count of arrivals.</p>
<p>Start excursion: the test start's own distance outside the training box (no rollout from it can do
better). Certified excursion bound: the farthest the certificate lets a trajectory from the start go
outside the box (docs/theory.md, "How far a trajectory can go"); it is never exceeded. DMP (time-indexed, no
certificate): the primitive of the training demo whose first sample is nearest the test start.</p>
<table><tr>{''.join(f'<th>{h}</th>' for h in head)}</tr>{''.join(rows)}</table>
{blocks_html(results.get("blocks"))}
{''.join(figs)}
<p>Wall time {results['meta']['wall_s']:.0f} s.</p></body></html>
"""
    path = Path(out_dir) / "index.html"
    path.write_text(page)
    return path

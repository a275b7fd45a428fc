"""Fig. 4: exemplar reproductions under a push (a, b) and a goal change (c, d), for
BendedLine and Leaf_1 (the paper's choice), every method on the same event (scenario 0:
demonstration 0). Drawn from the runs cached by the robustness evaluation.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from sosdyn.report.figures import (GOAL_STYLE, STYLE, method_color, perturbation_trajectories,
                                   save_figure)

from .findings import coincide
from .plumbing import Context, figure_main, figure_spec
from .settings import load_shape

SHAPES = ("BendedLine", "Leaf_1")


def figure(entries: dict, ctx: Context, shapes=SHAPES) -> dict:
    shapes = [s for s in ctx.shapes if s.name in shapes] or list(ctx.shapes)[:2]
    methods = [m for m in ctx.methods
               if any(entries.get(s.name, {}).get(m, {}).get("status") == "ok" for s in shapes)]
    if not methods:
        return {}
    panels = [(kind, s) for kind in ("push", "goal_change") for s in shapes]
    with mpl.rc_context(STYLE):
        fig = Figure(figsize=(4.2 * len(shapes), 8.9), layout="constrained")
        axes = fig.subplots(2, len(shapes), squeeze=False).ravel()
        for i, (ax, (kind, shp)) in enumerate(zip(axes, panels)):
            demo = load_shape(shp, ctx.config)[0]
            runs, events, goal_history = {}, {}, None
            for m in methods:
                e = entries.get(shp.name, {}).get(m)
                ex = (e or {}).get("plot", {}).get("exemplars", {}).get(kind) if e else None
                if not ex:
                    continue
                runs[m] = np.array(ex["pos"], dtype=float)
                events[m] = ex["events"]
                if goal_history is None:
                    goal_history = np.array(ex["goal_history"], dtype=float)
            label = "push" if kind == "push" else "goal change"
            perturbation_trajectories(ax, demo.pos, runs, events, goal_history,
                                      title=f"({'abcd'[i]}) {shp.name}: {label}")
        handles = [Line2D([], [], color="0.75", lw=5, alpha=0.8, label="demonstration")]
        handles += [Line2D([], [], color=method_color(m, methods), lw=1.6, label=m) for m in methods]
        handles += [Line2D([], [], color="black", lw=1.4, marker=">", markersize=5, label="push"),
                    Line2D([], [], label="old goal", **{**GOAL_STYLE, "markerfacecolor": "white",
                                                        "markeredgecolor": "black"}),
                    Line2D([], [], label="goal / new goal", **GOAL_STYLE)]
        fig.legend(handles=handles, loc="outside lower center", ncols=5)
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig4_perturbations")
    caption = ("Fig. 4 — exemplar reproductions of demonstration 1 under a sudden push (a, b; "
               "arrows from the state before to the state after, one per method) and a sudden goal "
               "change (c, d), same event for every method. The gray band is the demonstration "
               "(for c, d: before the change).")
    if all(m in methods for m in ("CDSP (paper)", "SEDS-like")) and coincide(entries, "CDSP (paper)",
                                                                             "SEDS-like"):
        caption += " CDSP (paper) and SEDS-like coincide (same reproductions)."
    return figure_spec("fig4", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 4: exemplar perturbed and goal-changed trajectories", figure,
                         shapes=SHAPES)

"""Fig. 4: exemplar reproductions under a push (a, b) and a goal change (c, d), for
BendedLine and Leaf_1 (the paper's choice), every method on the same event (scenario 0:
demonstration 0), one row of panels per method. Drawn from the runs cached by the
robustness evaluation.
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


def _exemplar(entries, shp, method, kind):
    """(positions, events, goal history) of the cached exemplar run, or None."""
    ex = ((entries.get(shp.name, {}).get(method) or {}).get("plot", {}).get("exemplars", {})
          .get(kind))
    if not ex:
        return None
    return (np.array(ex["pos"], dtype=float), ex["events"],
            np.array(ex["goal_history"], dtype=float))


def figure(entries: dict, ctx: Context, shapes=SHAPES) -> dict:
    """One row per method, one column per (perturbation, shape): each panel shows one
    method's run on the demonstration, so no two methods' lines hide each other."""
    shapes = [s for s in ctx.shapes if s.name in shapes] or list(ctx.shapes)[:2]
    methods = [m for m in ctx.methods
               if any(entries.get(s.name, {}).get(m, {}).get("status") == "ok" for s in shapes)]
    if not methods:
        return {}
    columns = [(kind, s) for kind in ("push", "goal_change") for s in shapes]
    demos = {s.name: load_shape(s, ctx.config)[0].pos for s in shapes}
    with mpl.rc_context({**STYLE, "axes.titlesize": 8.5, "axes.labelsize": 7.5,
                         "xtick.labelsize": 6.5, "ytick.labelsize": 6.5}):
        fig = Figure(figsize=(1.85 * len(columns) + 0.5, 1.8 * len(methods) + 0.7),
                     layout="constrained")
        axes = fig.subplots(len(methods), len(columns), squeeze=False)
        for r, method in enumerate(methods):
            for c, (kind, shp) in enumerate(columns):
                ax = axes[r, c]
                run = _exemplar(entries, shp, method, kind)
                if run is None:
                    ax.set_axis_off()
                    ax.text(0.5, 0.5, "not run", ha="center", va="center", transform=ax.transAxes,
                            color="0.5")
                    continue
                pos, events, goal_history = run
                label = "push" if kind == "push" else "goal change"
                perturbation_trajectories(ax, demos[shp.name], {method: pos}, events, goal_history,
                                          title=f"({'abcd'[c]}) {shp.name}\n{label}" if r == 0 else None,
                                          methods=methods)
                ax.set_xlabel("" if r < len(methods) - 1 else ax.get_xlabel())
                ax.set_ylabel(f"{method}\n{ax.get_ylabel()}" if c == 0 else "")
                if c == 0:
                    ax.yaxis.label.set_color(method_color(method, methods))
        handles = [Line2D([], [], color="0.75", lw=5, alpha=0.8, label="demonstration"),
                   Line2D([], [], color="0.3", lw=1.6, label="reproduction (row's colour)"),
                   Line2D([], [], color="black", lw=1.4, marker=">", markersize=5, label="push"),
                   Line2D([], [], label="old goal", **{**GOAL_STYLE, "markerfacecolor": "white",
                                                       "markeredgecolor": "black"}),
                   Line2D([], [], label="goal / new goal", **GOAL_STYLE)]
        fig.legend(handles=handles, loc="outside lower center", ncols=3)
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig4_perturbations")
    caption = ("Exemplar reproductions of demonstration 1, one row per method, under a sudden push "
               "(a, b; black arrow from the state before to the state after) and a sudden goal "
               "change (c, d), same event for every method. The gray band is the demonstration "
               "(for c, d: before the change).")
    if all(m in methods for m in ("CDSP (paper)", "SEDS-like")) and coincide(entries, "CDSP (paper)",
                                                                             "SEDS-like"):
        caption += " CDSP (paper) and SEDS-like coincide (same reproductions)."
    return figure_spec("fig4", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 4: exemplar perturbed and goal-changed trajectories", figure,
                         shapes=SHAPES)

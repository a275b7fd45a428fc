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
from matplotlib.ticker import MaxNLocator

from sosdyn.report.figures import (GOAL_STYLE, STYLE, method_color, perturbation_trajectories,
                                   save_figure)

from .findings import coincide
from .plumbing import Context, figure_main, figure_spec
from .results import results_sections
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


def _share_column_boxes(axes) -> None:
    """Every panel of a column gets the union of the column's limits (the panels share their
    axes) and at most 3 ticks per axis."""
    for col in axes.T:
        drawn = [ax for ax in col if ax.lines]
        if drawn:
            lo = np.min([[*ax.get_xlim(), *ax.get_ylim()][::2] for ax in drawn], axis=0)
            hi = np.max([[*ax.get_xlim(), *ax.get_ylim()][1::2] for ax in drawn], axis=0)
            col[0].set_xlim(lo[0], hi[0])
            col[0].set_ylim(lo[1], hi[1])
        for ax in col:
            ax.xaxis.set_major_locator(MaxNLocator(3))
            ax.yaxis.set_major_locator(MaxNLocator(3))


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
    # Drawn at print size (one A4 page: ~1.3 in per panel) with 8-pt text, 3 ticks per axis,
    # one box per column shared by its rows, x tick labels on the bottom row only.
    with mpl.rc_context({**STYLE, "axes.titlesize": 8.5, "axes.labelsize": 8,
                         "xtick.labelsize": 7.5, "ytick.labelsize": 7.5}):
        fig = Figure(figsize=(1.45 * len(columns) + 0.7, 1.3 * len(methods) + 0.9),
                     layout="constrained")
        axes = fig.subplots(len(methods), len(columns), squeeze=False, sharex="col", sharey="col")
        for r, method in enumerate(methods):
            for c, (kind, shp) in enumerate(columns):
                ax = axes[r, c]
                run = _exemplar(entries, shp, method, kind)
                if run is None:
                    ax.text(0.5, 0.5, "not run", ha="center", va="center", transform=ax.transAxes,
                            color="0.5")
                    continue
                pos, events, goal_history = run
                label = "push" if kind == "push" else "goal change"
                perturbation_trajectories(ax, demos[shp.name], {method: pos}, events, goal_history,
                                          title=f"({'abcd'[c]}) {shp.name}\n{label}" if r == 0 else None,
                                          methods=methods)
        _share_column_boxes(axes)
        for r, method in enumerate(methods):
            for c in range(len(columns)):
                ax = axes[r, c]
                ax.tick_params(labelbottom=r == len(methods) - 1)   # y labels stay: columns differ
                ax.set_xlabel(ax.get_xlabel() if r == len(methods) - 1 else "")
                ax.set_ylabel(method if c == 0 else "", color=method_color(method, methods),
                              fontweight="bold")
        handles = [Line2D([], [], color="0.75", lw=5, alpha=0.8, label="demonstration"),
                   Line2D([], [], color="0.3", lw=1.6, label="reproduction (row's colour)"),
                   Line2D([], [], color="black", lw=1.4, marker=">", markersize=5, label="push"),
                   Line2D([], [], label="old goal", **{**GOAL_STYLE, "markerfacecolor": "white",
                                                       "markeredgecolor": "black"}),
                   Line2D([], [], label="goal / new goal", **GOAL_STYLE)]
        fig.legend(handles=handles, loc="outside lower center", ncols=3 if len(columns) > 2 else 2)
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig4_perturbations")
    caption = ("Exemplar reproductions of demonstration 1, one row per method, under a sudden push "
               "(a, b; black arrow from the state before to the state after) and a sudden goal "
               "change (c, d), same event for every method; the panels of a column share their axes (mm). The gray band is the demonstration "
               "(for c, d: before the change).")
    same = coincide(results_sections(entries), "CDSP (paper)", "SEDS-like")
    if all(m in methods for m in ("CDSP (paper)", "SEDS-like")) and same:
        caption += " CDSP (paper) and SEDS-like coincide (same mean DTWD within 0.1 %)."
    return figure_spec("fig4", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 4: exemplar perturbed and goal-changed trajectories", figure,
                         shapes=SHAPES)

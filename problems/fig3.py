"""Fig. 3: robustness — DTWD to the (shifted) demonstrations after pushes and after goal changes.

Every method sees the same seeded events (``sosdyn.evaluation.perturbations.make_events``):
per demonstration one push (10 % of the data's bounding-box diagonal, random direction) and
one goal change of the same size, at 30 % of the demonstration's duration; scored by
``sosdyn.evaluation.perturbations.robustness``.
"""
from __future__ import annotations

from pathlib import Path

from sosdyn.report.figures import robustness_bars, save_figure

from .plumbing import Context, figure_main, figure_spec
from .results import results_sections


def figure(entries: dict, ctx: Context) -> dict:
    table = results_sections(entries)["robustness"]
    if not table:
        return {}
    fig = robustness_bars(table, metric="dtwd_total")
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig3_robustness")
    cfg = ctx.config
    caption = (f"DTWD between the reproductions and the demonstrations after a push "
               f"(top; {100 * cfg.push_amp:.0f} % of the data's bounding-box diagonal) and after a goal "
               f"change (bottom; {100 * cfg.goal_amp:.0f} %, reference shifted with the goal), both at "
               f"{100 * cfg.at_frac:.0f} % of each demonstration, same seeded events for every method; "
               f"each run lasts {cfg.duration_factor:g}x its demonstration, doubled until it ends within "
               f"{cfg.goal_tol:g} mm of its goal, at most {cfg.max_duration_factor:g}x. Point: median "
               "over the demonstrations; whisker: interquartile range (25th to 75th percentile); "
               f"hollow point: not every run ended within {cfg.goal_tol:g} mm of its goal.")
    return figure_spec("fig3", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 3: robustness after pushes and goal changes, median and IQR", figure)

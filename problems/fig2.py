"""Fig. 2: reproduction accuracy (SEA and DTWD, median and interquartile range over the demonstrations), all methods."""
from __future__ import annotations

from pathlib import Path

from sosdyn.report.figures import accuracy_bars, save_figure

from .plumbing import Context, figure_main, figure_spec
from .results import results_sections


def figure(entries: dict, ctx: Context) -> dict:
    table = results_sections(entries)["accuracy"]
    table = {s: {m: e for m, e in per.items() if "sea" in e} for s, per in table.items()}
    table = {s: per for s, per in table.items() if per}
    if not table:
        return {}
    fig = accuracy_bars(table, metrics=("sea", "dtwd_total"))
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig2_accuracy")
    n = max(len(e["sea"]["per_demo"]) for per in table.values() for e in per.values())
    caption = (f"Swept error area (SEA) and dynamic time warping distance (DTWD) between the {n} "
               "demonstrations and their reproductions, per shape and method: the point is the median "
               "over the demonstrations, the whisker the interquartile range (25th to 75th "
               "percentile); log axis where the medians span more than two decades. The tables give "
               "mean ± standard deviation.")
    return figure_spec("fig2", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 2: accuracy (SEA, DTWD) for all methods, median and IQR", figure)

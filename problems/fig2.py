"""Fig. 2: reproduction accuracy (SEA and DTWD, mean ± std over the demonstrations), all methods."""
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
    caption = (f"Fig. 2 — swept error area (SEA) and dynamic time warping distance (DTWD) between "
               f"the {n} demonstrations and their reproductions, mean ± one standard deviation, "
               "per shape and method (log axis where the values span more than two decades).")
    return figure_spec("fig2", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 2: accuracy bars (SEA, DTWD) for all methods", figure)

"""Fig. 1: streamlines of the learned fields with demonstrations and reproductions.

Four shapes (paper: BendedLine, DoubleBendedLine, Leaf_1, Leaf_2), fitted with the default
model ``CDSP()`` (method "CDSP" of :mod:`problems.settings`). The fields are cached on the
plot lattice, so redrawing does not refit.
"""
from __future__ import annotations

from pathlib import Path

from sosdyn.report.figures import save_figure, streamline_panel

from .lattice import field_panel
from .plumbing import Context, figure_main, figure_spec
from .settings import DEFAULT_METHOD

METHODS = (DEFAULT_METHOD,)


def figure(entries: dict, ctx: Context, methods=METHODS) -> dict:
    panels = [field_panel(entries.get(shp.name, {}).get(method), shp, ctx.config, f"{shp.name}: {method}")
              for method in methods for shp in ctx.shapes]
    panels = [p for p in panels if p]
    if not panels:
        return {}
    fig = streamline_panel(panels, ncols=min(len(ctx.shapes), 4))
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig1_streamlines")
    shown = [m for m in methods if any(p["title"].endswith(m) for p in panels)]
    cfg = ctx.config
    caption = ("Learned models of the LASA shapes, fitted with "
               + ", ".join("the default CDSP()" if m == DEFAULT_METHOD else m for m in shown)
               + ": streamlines of the field (gray), the demonstrations (solid red), and the "
               "reproductions from the demonstrations' starts (dashed blue), each rolled out until "
               f"it is within {cfg.goal_tol:g} mm of the goal (at most {cfg.max_duration_factor:g}x "
               "its demonstration's duration).")
    return figure_spec("fig1", paths, ctx.out_dir, caption)


def main(argv=None):
    return figure_main(argv, "Fig. 1: streamlines of the default CDSP() on the paper's shapes",
                       figure, methods=METHODS)

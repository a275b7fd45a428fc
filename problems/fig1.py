"""Fig. 1: streamlines of the learned fields with demonstrations and reproductions.

Four shapes (paper: BendedLine, DoubleBendedLine, Leaf_1, Leaf_2); one row per method
(CDSP-cubic and CDSP-ICA). The fields are cached on the plot lattice, so redrawing does
not refit.
"""
from __future__ import annotations

from pathlib import Path

from problems import common as C

METHODS = ("CDSP-cubic", "CDSP-ICA")


def figure(entries: dict, ctx: C.Context, methods=METHODS) -> dict:
    from sosdyn.report.figures import save_figure, streamline_panel
    panels = []
    for method in methods:
        for shp in ctx.shapes:
            e = entries.get(shp.name, {}).get(method)
            if not e or e.get("status") != "ok" or "field" not in e.get("plot", {}):
                continue
            demos = C.load_shape(shp, ctx.config)
            fld = e["plot"]["field"]
            panels.append({"predict": C.CachedField(fld), "demos_pos": [d.pos for d in demos],
                           "reproductions": e["plot"]["reproductions"], "goal": demos.goal,
                           "bounds": fld["bounds"], "grid": fld["grid"],
                           "title": f"{shp.name}: {method}"})
    if not panels:
        return {}
    fig = streamline_panel(panels, ncols=min(len(ctx.shapes), 4))
    paths = save_figure(fig, Path(ctx.fig_dir) / "fig1_streamlines")
    shown = [m for m in methods if any(p["title"].endswith(m) for p in panels)]
    caption = ("Fig. 1 — learned models of the LASA shapes, one row per method ("
               + ", ".join(shown) + "): streamlines of the field (gray), the demonstrations (solid "
               "red), and the reproductions from the demonstrations' starts (dashed blue).")
    return C.figure_spec("fig1", paths, ctx.out_dir, caption)


def main(argv=None):
    return C.figure_main(argv, "Fig. 1: streamlines of CDSP-cubic and CDSP-ICA on the paper's shapes",
                         figure, methods=METHODS)

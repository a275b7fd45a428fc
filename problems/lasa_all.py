"""All 30 LASA shapes x all methods (K = 6 everywhere): a table and a grid of streamline plots.

Slow (about 30 x the per-shape cost of ``make run``): ``make lasa-all``. Results are cached
per (shape, method) in ``reports/cache/lasa_all`` (apart from the main run's cache: the
entries differ, e.g. no Fig. 4 exemplars); the report goes to
``reports/lasa_all/`` (index.html, report.pdf) and the grid figure to
``reports/figures/lasa_all.png``, which the main report includes when present.
"""
from __future__ import annotations

import time
from pathlib import Path

import sosdyn as sd
from sosdyn.report.figures import save_figure, streamline_panel
from sosdyn.report.html import build_report, render_html

from .fig2 import figure as fig2
from .jobs import evaluate_all
from .jsonio import write_json
from .lattice import field_panel
from .plumbing import Context, parse_args
from .results import assemble, relpath
from .settings import METHOD_ORDER, METHODS, REPORTS, EvalConfig, shape

FIELD_METHOD = "CDSP-cubic"


def run(names, methods, config: EvalConfig, out_dir=REPORTS, *, n_jobs=2, K=6,
        field_method=FIELD_METHOD, cache_dir=None, force=False, render_pdf=True) -> dict:
    out_dir = Path(out_dir)
    shapes = tuple(shape(n, K=K) for n in names)
    entries = evaluate_all(shapes, methods, config=config, n_jobs=n_jobs,
                           cache_dir=cache_dir or out_dir / "cache" / "lasa_all", force=force)
    field_method = field_method if field_method in methods else next(
        (m for m in methods if METHODS[m].plot_field), None)
    panels = [field_panel(entries[s.name].get(field_method), s, config, s.name) for s in shapes]
    panels = [p for p in panels if p]
    figures = {}
    sub = out_dir / "lasa_all"
    if panels:
        fig = streamline_panel(panels, ncols=6 if len(panels) > 8 else min(len(panels), 4),
                               panel_size=2.3)
        paths = save_figure(fig, out_dir / "figures" / "lasa_all", dpi=110)
        caption = (f"All {len(panels)} LASA shapes, {field_method} (K = {K}): streamlines, "
                   "demonstrations (red) and reproductions (dashed blue). Full table: "
                   "reports/lasa_all/index.html.")
        (out_dir / "figures" / "lasa_all.caption.txt").write_text(caption)
        figures["lasa_all"] = {"svg": relpath(paths["svg"], sub), "png": relpath(paths["png"], sub),
                               "caption": caption}
    figures.update(fig2(entries, Context(shapes=shapes, config=config, out_dir=sub, methods=methods)))
    results = assemble(entries, shapes, methods, config, figures, bench=False,
                       meta_extra={"n_shapes": len(shapes), "K": K})
    path = write_json(sub / "results.json", results)
    if render_pdf:   # trusted: the grid figure sits in ../figures, shared with the main report
        return build_report(path, sub, trusted=True)
    return {"html": render_html(results, sub, trusted=True)}


def main(argv=None):
    args = parse_args(argv, "All 30 LASA shapes x methods (slow)")
    names = args.shapes or sd.lasa_names()
    config = EvalConfig(quick=args.quick, n_grid=5, field_grid=50)
    t0 = time.perf_counter()
    paths = run(names, METHOD_ORDER, config, args.out, n_jobs=args.jobs, force=args.force)
    print(f"lasa-all: {paths['html']} ({time.perf_counter() - t0:.1f} s)")
    return 0

"""All 30 LASA shapes x all methods (K = 6 everywhere): a table and pages of streamline plots.

Slow (about 30 x the per-shape cost of ``make run``): ``make lasa-all``. Results are cached
per (shape, method) in ``reports/cache/lasa_all`` (apart from the main run's cache: the
entries differ, e.g. no Fig. 4 exemplars); the report goes to
``reports/lasa_all/`` (index.html, report.pdf) and the streamline figures, ``PER_PAGE``
shapes each (readable on A4), to ``reports/figures/lasa_all.png``, ``lasa_all_2.png``, ...,
which the main report includes when present.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import sosdyn as sd
from sosdyn.report.figures import save_figure, streamline_panel
from sosdyn.report.html import build_report, render_html

from .fig2 import figure as fig2
from .jobs import evaluate_all, take_scheduler_argument
from .jsonio import write_json
from .lattice import field_panel
from .plumbing import Context, parse_args
from .results import assemble, relpath
from .settings import DEFAULT_METHOD, METHOD_ORDER, METHODS, REPORTS, EvalConfig, shape

FIELD_METHOD = DEFAULT_METHOD
#: How the captions name the default model (the user report includes only pages drawn with it).
DEFAULT_LABEL = "the default CDSP()"
#: Streamline panels per figure (3 columns x 2 rows fills an A4 page width).
PER_PAGE = 6


def page_names(n_panels: int, per_page: int = PER_PAGE) -> list[str]:
    """Figure names of the pages: ``lasa_all``, ``lasa_all_2``, ``lasa_all_3``, ..."""
    return ["lasa_all" if k == 0 else f"lasa_all_{k + 1}" for k in range(-(-n_panels // per_page))]


def _title(name: str, entry) -> str:
    """Panel title: the shape and its mean DTWD over the demonstrations (as in the table)."""
    dtwd = (((entry or {}).get("accuracy") or {}).get("dtwd_total") or {}).get("mean")
    return name if dtwd is None else f"{name} (DTWD {dtwd:.0f} mm)"


def draw_pages(panels: list, out_dir: Path, sub: Path, field_method: str, K: int) -> dict:
    """The streamline panels ``PER_PAGE`` to a figure; stale pages of an earlier, longer run
    are removed. Returns the figure specs (paths relative to ``sub``)."""
    fig_dir = out_dir / "figures"
    names = page_names(len(panels))
    for old in fig_dir.glob("lasa_all_*"):
        if old.name.split(".")[0] not in names:
            old.unlink()
    figures = {}
    for k, name in enumerate(names):
        chunk = panels[k * PER_PAGE:(k + 1) * PER_PAGE]
        fig = streamline_panel(chunk, ncols=3, panel_size=3.1)
        paths = save_figure(fig, fig_dir / name, dpi=130)
        first, last = k * PER_PAGE + 1, k * PER_PAGE + len(chunk)
        model = DEFAULT_LABEL if field_method == DEFAULT_METHOD else f"{field_method} (K = {K})"
        caption = (f"LASA shapes {first}-{last} of {len(panels)}, {model}: "
                   "streamlines, demonstrations (red) and reproductions (dashed blue); the panel title gives the mean DTWD over the demonstrations. "
                   "Full table: reports/lasa_all/index.html.")
        (fig_dir / f"{name}.caption.txt").write_text(caption)
        figures[name] = {"svg": relpath(paths["svg"], sub), "png": relpath(paths["png"], sub),
                         "caption": caption}
    return figures


def run(names, methods, config: EvalConfig, out_dir=REPORTS, *, n_jobs=2, K=6,
        field_method=FIELD_METHOD, cache_dir=None, force=False, render_pdf=True) -> dict:
    out_dir = Path(out_dir)
    shapes = tuple(shape(n, K=K) for n in names)
    entries = evaluate_all(shapes, methods, config=config, n_jobs=n_jobs,
                           cache_dir=cache_dir or out_dir / "cache" / "lasa_all", force=force)
    field_method = field_method if field_method in methods else next(
        (m for m in methods if METHODS[m].plot_field), None)
    panels = [field_panel(entries[s.name].get(field_method), s, config,
                          _title(s.name, entries[s.name].get(field_method))) for s in shapes]
    panels = [p for p in panels if p]
    sub = out_dir / "lasa_all"
    figures = draw_pages(panels, out_dir, sub, field_method, K) if panels else {}
    figures.update(fig2(entries, Context(shapes=shapes, config=config, out_dir=sub, methods=methods)))
    results = assemble(entries, shapes, methods, config, figures,
                       meta_extra={"n_shapes": len(shapes), "K": K})
    path = write_json(sub / "results.json", results)
    if render_pdf:   # trusted: the grid figure sits in ../figures, shared with the main report
        return build_report(path, sub, trusted=True)
    return {"html": render_html(results, sub, trusted=True)}


def take_methods_argument(argv) -> tuple[tuple, list]:
    """``(methods, rest of argv)`` from ``--methods NAME ...`` (default: every method)."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--methods", nargs="+", choices=METHOD_ORDER, default=METHOD_ORDER)
    args, rest = parser.parse_known_args(list(argv or []))
    return tuple(args.methods), rest


def main(argv=None):
    methods, argv = take_methods_argument(take_scheduler_argument(argv))
    args = parse_args(argv, "All 30 LASA shapes x methods (slow; --scheduler ADDRESS: on a Dask cluster; "
                      "--methods NAME ...: only these, e.g. --methods CDSP for the per-shape figures)")
    names = args.shapes or sd.lasa_names()
    config = EvalConfig(quick=args.quick, n_grid=5, field_grid=50)
    t0 = time.perf_counter()
    paths = run(names, methods, config, args.out, n_jobs=args.jobs, force=args.force)
    print(f"lasa-all: {paths['html']} ({time.perf_counter() - t0:.1f} s)")
    return 0

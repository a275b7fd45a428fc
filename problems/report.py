"""``make report`` / ``python -m problems report``: rebuild results.json, the figures,
``reports/index.html`` and ``reports/report.pdf`` (the user report) from the cached experiment
entries (no refitting; pairs that are not cached are shown as "not run"), and the benchmark
report ``reports/bench/index.html`` from what the benchmarks wrote there. Without a cache (a fresh
clone) the user report is rendered again from its ``results.json``: the findings, the methods'
descriptions and the index of all reports are written anew from the data, the tables and figures
are those of the run that made it.

The user report opens with the index of every report under ``reports/``
(:mod:`problems.report_pages`), each with one finding read from that page's own data.

Not to be confused with ``sosdyn report --results FILE``, which only renders an existing
results file into HTML and PDF.
"""
from __future__ import annotations

import time
from pathlib import Path

from sosdyn.report.bench import render_bench
from sosdyn.report.html import build_report, load_results

from . import fig1, fig2, fig3, fig4
from .cache import cached_entries
from .lasa_all import DEFAULT_LABEL
from .plumbing import Context, context_from_args, parse_args
from .jsonio import write_json
from .findings import findings
from .report_pages import index_pages
from .results import assemble, meta, redescribed, relpath

#: Figures other experiments write (lasa-all, demo3d), included when present; each may
#: have further pages ``<name>_2``, ``<name>_3``, ...
EXTRA_FIGURES = ("demo3d", "lasa_all")


def draw_figures(entries: dict, ctx: Context) -> dict:
    """Figs. 1-4 from the entries and the extra figures already on disk, in print order: Figs.
    1-3, the 3-D demo (half a page, next to Fig. 3), Fig. 4 (a full page), the per-shape pages."""
    figures = {}
    for mod in (fig1, fig2, fig3):
        figures.update(mod.figure(entries, ctx))
    drawn_fig4 = fig4.figure(entries, ctx)
    for extra in EXTRA_FIGURES:
        for name in _pages(ctx, extra):
            spec = _existing_figure(ctx, name)
            if spec and (extra != "lasa_all" or DEFAULT_LABEL in spec["caption"]):
                figures[name] = spec     # per-shape pages only when they show the default CDSP()
        if extra == "demo3d":
            figures.update(drawn_fig4)   # after the half-page 3-D figure, which shares Fig. 3's page
    return figures


def _pages(ctx, name):
    """``name`` and its further pages ``name_2``, ``name_3``, ... found on disk, in order."""
    rest = [p.stem[len(name) + 1:] for p in Path(ctx.fig_dir).glob(f"{name}_*.png")]
    return [name, *(f"{name}_{k}" for k in sorted(int(r) for r in rest if r.isdigit()))]


def _existing_figure(ctx, name):
    """A figure written by another experiment (lasa-all, demo3d), with its caption file."""
    png = Path(ctx.fig_dir) / f"{name}.png"
    cap = Path(ctx.fig_dir) / f"{name}.caption.txt"
    if not png.is_file():
        return None
    svg = png.with_suffix(".svg")
    spec = {"png": relpath(png, ctx.out_dir), "caption": cap.read_text() if cap.is_file() else name}
    if svg.is_file():
        spec["svg"] = relpath(svg, ctx.out_dir)
    return spec


def build(entries: dict, ctx: Context, *, extra_meta=None, command=None) -> dict:
    """Draw the figures, write ``results.json`` and render index.html + report.pdf; also
    ``bench/index.html`` (key ``"bench"``) when the output folder has a ``bench/`` folder."""
    figures = draw_figures(entries, ctx)
    results = assemble(entries, ctx.shapes, ctx.methods, ctx.config, figures, command=command,
                       meta_extra={"quick": ctx.config.quick, **(extra_meta or {})})
    return _render(results, ctx)


def rebuild(ctx: Context) -> dict:
    """The user report again from ``results.json`` alone: findings, method descriptions and the
    index of all reports written anew from its data; tables, figures and meta as they were."""
    results = load_results(Path(ctx.out_dir) / "results.json")
    results.update(findings=findings(results), methods=redescribed(results.get("methods") or {}))
    now = meta()
    results["meta"]["rendered_again"] = (f"{now['created']}, commit {now['git_commit']}: findings, method "
                                         "descriptions and the index written again from this data")
    return _render(results, ctx)


def _render(results: dict, ctx: Context) -> dict:
    """Index the reports into ``results``, write it and render the pages (the benchmark page
    first: the index reads it)."""
    bench_dir = Path(ctx.out_dir) / "bench"
    bench = render_bench(bench_dir) if bench_dir.is_dir() else None
    results["pages"] = index_pages(ctx.out_dir, results)
    path = write_json(Path(ctx.out_dir) / "results.json", results)
    paths = build_report(path, ctx.out_dir)
    return {**paths, "bench": bench} if bench else paths


def main(argv=None):
    args = parse_args(argv, "Rebuild results.json and the report from the cached experiment entries "
                            "(no refitting); without a cache, from results.json")
    ctx = context_from_args(args)
    t0 = time.perf_counter()
    entries = cached_entries(ctx.shapes, ctx.methods, config=ctx.config, cache_dir=ctx.cache_dir)
    n = sum(len(v) for v in entries.values())
    print(f"{n} cached results of {len(ctx.shapes) * len(ctx.methods)} in {ctx.cache_dir}")
    if n == 0 and (Path(ctx.out_dir) / "results.json").is_file():
        print(f"no cache: rendering {Path(ctx.out_dir) / 'results.json'} again (findings and index from its data)")
        paths = rebuild(ctx)
    else:
        paths = build(entries, ctx)
    print(f"report: {paths['html']} and {paths['pdf']}"
          f"{' (benchmarks: ' + str(paths['bench']) + ')' if 'bench' in paths else ''} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0

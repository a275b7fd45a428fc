"""The main job (``make run``): the paper's four LASA shapes, every method, Figs. 1-4,
the findings, and ``reports/index.html`` + ``reports/report.pdf``.

Fits and evaluations run in 2 worker processes and are cached under ``reports/cache``;
a second run only redraws and re-renders. ``--quick`` uses reduced fits and a 5x5 grid.
"""
from __future__ import annotations

import time

from . import report
from .findings import failures
from .jobs import evaluate_all
from .plumbing import context_from_args, parse_args
from .results import results_sections


def main(argv=None):
    args = parse_args(argv, "Paper shapes x methods, Figs. 1-4, findings and the report")
    ctx = context_from_args(args)
    t0 = time.perf_counter()
    print(f"sosdyn run: {len(ctx.shapes)} shapes x {len(ctx.methods)} methods on {ctx.n_jobs} "
          f"processes (cache: {ctx.cache_dir})", flush=True)
    entries = evaluate_all(ctx.shapes, ctx.methods, config=ctx.config, n_jobs=ctx.n_jobs,
                           cache_dir=ctx.cache_dir, force=args.force)
    t_fit = time.perf_counter() - t0
    print(f"fits and evaluations: {t_fit:.1f} s; drawing figures and rendering the report", flush=True)
    paths = report.build(entries, ctx, extra_meta={"n_jobs": ctx.n_jobs,
                                                   "fit_and_evaluate_wall_s": round(t_fit, 1)})
    for s, m, err in failures(results_sections(entries)):
        print(f"FAILED {s} / {m}: {err}")
    print(f"done in {time.perf_counter() - t0:.1f} s: {paths['html']}  {paths['pdf']}")
    return 0

"""Command-line plumbing of the experiments: common options, the context they run in, the
``main`` of a figure experiment."""
from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from .jobs import evaluate_all
from .results import relpath
from .settings import METHOD_ORDER, PAPER_SHAPES, REPORTS, EvalConfig, Shape, shape


@dataclass
class Context:
    """Where an experiment reads and writes: shapes, config, cache and output folders."""

    shapes: Sequence[Shape] = PAPER_SHAPES
    config: EvalConfig = field(default_factory=EvalConfig)
    out_dir: Path = REPORTS
    cache_dir: Path | None = None
    n_jobs: int = 2
    methods: Sequence[str] = METHOD_ORDER

    @property
    def fig_dir(self) -> Path:
        return Path(self.out_dir) / "figures"


def parse_args(argv, description: str) -> argparse.Namespace:
    """Common command-line options of the experiments."""
    p = argparse.ArgumentParser(prog="python -m problems", description=description)
    p.add_argument("--quick", action="store_true", help="quick settings (smaller fits and grid)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--shapes", nargs="*", default=None, help="LASA shapes (default: the paper's four)")
    p.add_argument("--force", action="store_true", help="refit even when cached")
    p.add_argument("--out", type=Path, default=REPORTS, help="output folder (default reports/)")
    return p.parse_args(list(argv or []))


def context_from_args(args) -> Context:
    shapes = tuple(shape(n) for n in args.shapes) if args.shapes else PAPER_SHAPES
    # 5x5: the batched grid is cheap for CDSP (~1-3 s at 10x10) but not for CLF-DM, whose
    # switched correction makes every integrator crawl (60-135 s per shape at 10x10).
    config = EvalConfig(quick=args.quick, n_grid=5)
    out = Path(args.out)
    return Context(shapes=shapes, config=config, out_dir=out, cache_dir=out / "cache", n_jobs=args.jobs)


def figure_spec(name: str, paths: dict, out_dir, caption: str) -> dict:
    """``{name: {svg, png, caption}}`` with paths relative to the report folder."""
    return {name: {"svg": relpath(paths["svg"], out_dir), "png": relpath(paths["png"], out_dir),
                   "caption": caption}}


def figure_main(argv, description: str, figure: Callable, methods=None, shapes=None) -> int:
    """The ``main`` of a figure experiment: fit/evaluate (cached), draw, print the paths."""
    args = parse_args(argv, description)
    ctx = context_from_args(args)
    if shapes:
        ctx.shapes = tuple(s for s in ctx.shapes if s.name in shapes) or ctx.shapes
    entries = evaluate_all(ctx.shapes, methods or ctx.methods, config=ctx.config, n_jobs=ctx.n_jobs,
                           cache_dir=ctx.cache_dir, force=args.force)
    for name, spec in figure(entries, ctx).items():
        print(f"{name}: {ctx.out_dir / spec['png']}")
    return 0

"""The default's overhead (issue 26 item 1): ``CDSP()`` against its own plain core ``CDSP(warp="none")``.

On the paper's four LASA shapes, in one process: one warm-up fit (the first fit of a process pays
one-off costs, imports and first calls, that neither side should carry), then per shape the core
fit and the default fit, alternately. Reports each time (process CPU time, which other processes
on a shared machine disturb less than the wall clock; the wall times too), the sum over shapes and
the ratio default / core in CPU time (target: <= 2), and the default's split from ``model.timings_``: ``candidates_s``
(its warp candidates: a greedy warp fit per warp and a core fit per candidate, one of them the plain
core itself) and ``choice_s`` (the training rollouts that score them); the floor of the ratio is the
candidates' core fits, about (1 + len(AUTO_WARPS)) x the core. ``python -m problems bench --skip ...`` runs it as the
part ``overhead`` (``overhead.json``); alone: ``python -m problems.bench.default_overhead``.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from sosdyn.lfd import CDSP, load_lasa
from sosdyn.lfd.fit.params import PLAIN

from ..settings import BENCH, PAPER_SHAPES
from .timing import environment, fmt_s, now, timing, write_json

TARGET = 2.0                # issue 26: default fit <= 2 x its plain core, sum over the paper's shapes
WARM_UP = "Angle"           # not one of the paper's shapes


def run(quick: bool = False, log=print) -> dict:
    """Core and default fits of the paper's shapes (module docstring); ``quick``: one shape, small fits."""
    shapes = [s.name for s in PAPER_SHAPES][:1 if quick else None]
    small = dict(max_iter=2, verify_samples=500, max_samples=500) if quick else {}
    CDSP(**PLAIN, **small).fit(load_lasa(WARM_UP))
    rows = []
    for name in shapes:
        demos = load_lasa(name)
        t0, c0 = now(), time.process_time()
        CDSP(**PLAIN, **small).fit(demos)
        core, core_cpu = now() - t0, time.process_time() - c0
        t0, c0 = now(), time.process_time()
        model = CDSP(**small).fit(demos)
        default, default_cpu = now() - t0, time.process_time() - c0
        T = model.timings_
        rows.append({"shape": name, "core_s": core_cpu, "default_s": default_cpu, "ratio": default_cpu / core_cpu,
                     "core_wall_s": core, "default_wall_s": default,
                     "candidates_s": timing(T, "candidates_s", "model.timings_"),
                     "choice_s": timing(T, "choice_s", "model.timings_"), "warp_scores": model.warp_scores_,
                     "kept": min(model.warp_scores_, key=model.warp_scores_.get)})
        log(f"overhead: {name:17s} core {fmt_s(core_cpu):>8s} default {fmt_s(default_cpu):>8s} CPU "
            f"({default_cpu / core_cpu:.1f}x; wall {fmt_s(core)} / {fmt_s(default)}; candidates "
            f"{fmt_s(rows[-1]['candidates_s'])}, choice {fmt_s(rows[-1]['choice_s'])} wall; kept {rows[-1]['kept']!r})")
    core, default = sum(r["core_s"] for r in rows), sum(r["default_s"] for r in rows)
    wall = sum(r["core_wall_s"] for r in rows), sum(r["default_wall_s"] for r in rows)
    res = {"shapes": rows, "core_s": core, "default_s": default, "ratio": default / core, "target": TARGET,
           "met": default / core <= TARGET, "clock": "process CPU time", "wall_ratio": wall[1] / wall[0],
           "candidates_over_core": sum(r["candidates_s"] for r in rows) / wall[0],
           "choice_over_core": sum(r["choice_s"] for r in rows) / wall[0]}
    log(f"overhead: sum: core {fmt_s(core)}, default {fmt_s(default)} CPU: {res['ratio']:.2f}x (target <= {TARGET}; "
        f"wall {res['wall_ratio']:.2f}x); candidates {res['candidates_over_core']:.2f}x core, choice "
        f"{res['choice_over_core']:.2f}x core (wall)")
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m problems.bench.default_overhead")
    ap.add_argument("--quick", action="store_true", help="one shape, small fits (smoke test)")
    ap.add_argument("--out", default=str(BENCH))
    args = ap.parse_args(argv)
    res = run(args.quick)
    write_json(Path(args.out) / "overhead.json", {"environment": environment(), **res})
    return 0


if __name__ == "__main__":
    sys.exit(main())

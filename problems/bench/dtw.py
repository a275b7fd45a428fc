"""The DTW distance's speed (:func:`sosdyn.evaluation.metrics.dtwd`, dtaidistance's C routine): 2-D random
walks of 1000 x 1000 and 3000 x 500 points, the median of ``--repeats`` calls after one warm-up, against
the targets TARGETS_S (what the unit tests asserted in seconds until they became benchmark targets; the
unit tests check that the C routine runs, once, and never the pure-Python loop).
Writes ``reports/bench/dtw.json``. Run: ``python -m problems.bench.dtw [--quick]``.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from sosdyn.evaluation.metrics import dtwd

from ..settings import BENCH
from .timing import environment, median, now, write_json

TARGETS_S = {(1000, 1000): 0.5, (3000, 500): 1.0}


def run(repeats: int) -> dict:
    """{"rows": one per size (points, median seconds, target, met), "met": all met}."""
    rng = np.random.default_rng(0)
    rows = []
    for (N, M), target in TARGETS_S.items():
        a, b = (np.cumsum(rng.standard_normal((k, 2)), axis=0) for k in (N, M))
        dtwd(a, b)
        ts = []
        for _ in range(repeats):
            t0 = now()
            dtwd(a, b)
            ts.append(now() - t0)
        rows.append({"points": [N, M], "median_s": median(ts), "target_s": target, "met": median(ts) <= target,
                     "repeats": repeats})
    return {"rows": rows, "met": all(r["met"] for r in rows)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m problems.bench.dtw", description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=20, help="timed calls per size (default: %(default)s)")
    ap.add_argument("--quick", action="store_true", help="3 calls per size (smoke test)")
    ap.add_argument("--out", default=str(BENCH), help="output folder (default: reports/bench)")
    args = ap.parse_args(argv)
    res = run(3 if args.quick else args.repeats)
    for r in res["rows"]:
        print(f"DTW {r['points'][0]} x {r['points'][1]}: {r['median_s'] * 1e3:.1f} ms (target "
              f"{r['target_s']:g} s)", flush=True)
    path = write_json(Path(args.out) / "dtw.json", {**res, "environment": environment()})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

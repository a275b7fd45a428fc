"""Timing and table helpers shared by the benchmarks; reading the SOS timings a solve records."""
from __future__ import annotations

import os
import platform
import statistics
import time
from pathlib import Path

import clarabel
import cvxpy
import numpy as np
import scipy

from ..jsonio import write_json as _write_json


def now() -> float:
    return time.perf_counter()


def median(xs):
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    return float(statistics.median(xs)) if xs else float("nan")


def environment() -> dict:
    """Versions and machine of the run."""
    return {"python": platform.python_version(), "machine": platform.machine(),
           "processor": platform.processor() or platform.machine(), "numpy": np.__version__,
           "scipy": scipy.__version__, "cvxpy": cvxpy.__version__,
           "clarabel": getattr(clarabel, "__version__", "?"), "cpus": os.cpu_count()}


def write_json(path: Path, data: dict) -> Path:
    """Strict JSON (non-finite numbers as null), for readers other than Python's."""
    return _write_json(path, data, finite_only=True)


def fmt_s(x, digits=3) -> str:
    """Seconds in a readable unit."""
    if x is None or not np.isfinite(x):
        return "–"
    if x >= 1:
        return f"{x:.2f} s"
    if x >= 1e-3:
        return f"{x * 1e3:.1f} ms"
    return f"{x * 1e6:.0f} µs"


def fmt_ratio(x) -> str:
    if x is None or not np.isfinite(x):
        return "–"
    if x >= 100:
        return f"{x:.0f}×"
    if x >= 10:
        return f"{x:.1f}×"
    return f"{x:.2f}×"


def md_table(header, rows) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def verdict(met: bool | None) -> str:
    return "–" if met is None else ("**met**" if met else "**missed**")




def timing(timings: dict, key: str, what: str) -> float:
    """``timings[key]`` (seconds), or KeyError saying which recorded timing is missing: the
    benchmark reads only public timing data and refuses to report a silent 0."""
    try:
        return float(timings[key])
    except KeyError:
        raise KeyError(f"{what} records no {key!r} timing (has: {', '.join(timings) or 'none'}); "
                       "the benchmark cannot split the time without it") from None

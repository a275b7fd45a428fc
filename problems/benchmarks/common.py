"""Timing, instrumentation, profiling and report-writing helpers shared by the benchmarks."""
from __future__ import annotations

import contextlib
import io
import json
import math
import platform
import statistics
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT_DIR = ROOT / "reports" / "bench"


def now() -> float:
    return time.perf_counter()


def median(xs):
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    return float(statistics.median(xs)) if xs else float("nan")


def environment() -> dict:
    import clarabel
    import cvxpy
    import scipy
    out = {"python": platform.python_version(), "machine": platform.machine(),
           "processor": platform.processor() or platform.machine(), "numpy": np.__version__,
           "scipy": scipy.__version__, "cvxpy": cvxpy.__version__,
           "clarabel": getattr(clarabel, "__version__", "?")}
    try:
        import os
        out["cpus"] = os.cpu_count()
    except Exception:  # noqa: BLE001
        pass
    return out


def _clean(obj):
    """JSON-safe copy: numpy scalars to Python, NaN/inf to None."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def write_json(path: Path, data: dict) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_clean(data), indent=1) + "\n")
    return path


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


# ---------------------------------------------------------------------- instrumentation
class Meter:
    """Accumulates where the SOS path spends time while active (monkeypatches, restored on exit).

    * ``solver``     -- seconds inside Clarabel's solve (as the back end reports it);
    * ``clarabel_setup`` -- the rest of the direct back end's call (matrix stacking, solver setup);
    * ``assemble``   -- ``sosdyn.sos.conic.assemble`` (the conic form of a program);
    * ``update``     -- ``SOSConstraint.update`` / ``FamilySOSConstraint.set_weights`` (the
      compile-once re-solve path);
    * ``cvxpy``      -- cvxpy back end call minus its solver time;
    * ``solves``     -- number of solver calls.
    """

    def __init__(self):
        self.t = {"solver": 0.0, "clarabel_setup": 0.0, "assemble": 0.0, "update": 0.0, "cvxpy": 0.0}
        self.solves = 0

    @contextlib.contextmanager
    def active(self):
        from sosdyn.sos import backends, conic, program
        orig = (backends._clarabel, backends._cvxpy, conic.assemble, program.SOSConstraint.update)
        family = getattr(program, "FamilySOSConstraint", None)
        orig_weights = getattr(family, "set_weights", None) if family is not None else None
        meter = self

        def clarabel_(*a, **k):
            t0 = now()
            out = orig[0](*a, **k)
            total = now() - t0
            meter.t["solver"] += out[3]
            meter.t["clarabel_setup"] += total - out[3]
            meter.solves += 1
            return out

        def cvxpy_(*a, **k):
            t0 = now()
            out = orig[1](*a, **k)
            total = now() - t0
            solver = out[4].get("solver_seconds") or out[3]
            meter.t["solver"] += solver
            meter.t["cvxpy"] += total - solver
            meter.solves += 1
            return out

        def timed(fn, key):
            def wrapper(*a, **k):
                t0 = now()
                try:
                    return fn(*a, **k)
                finally:
                    meter.t[key] += now() - t0
            return wrapper

        assemble_ = timed(orig[2], "assemble")
        update_ = timed(orig[3], "update")
        weights_ = timed(orig_weights, "update")

        backends._clarabel, backends._cvxpy, conic.assemble = clarabel_, cvxpy_, assemble_
        program.SOSConstraint.update = update_
        if orig_weights is not None:
            family.set_weights = weights_
        try:
            yield self
        finally:
            backends._clarabel, backends._cvxpy, conic.assemble, program.SOSConstraint.update = orig
            if orig_weights is not None:
                family.set_weights = orig_weights


# ---------------------------------------------------------------------- profiling
def profile_call(fn, top=15, interval=0.001):
    """Run ``fn`` under pyinstrument (cProfile as fallback); return (result, profile dict).

    The profile dict lists the functions with the largest *self* time (own code, not
    callees) and the largest *total* time among sosdyn functions, each with its share.
    """
    try:
        from pyinstrument import Profiler
    except ImportError:  # pragma: no cover
        return _cprofile_call(fn, top)
    prof = Profiler(interval=interval)
    prof.start()
    try:
        result = fn()
    finally:
        prof.stop()
    session = prof.last_session
    total = session.duration
    self_t, incl = {}, {}

    def walk(frame, stack):
        key = f"{frame.function} ({_short_path(frame.file_path)}:{frame.line_no})"
        self_t[key] = self_t.get(key, 0.0) + frame.total_self_time
        if key not in stack:          # count recursive frames once
            incl[key] = incl.get(key, 0.0) + frame.time
        for child in frame.children:
            walk(child, stack | {key})

    root = session.root_frame()
    if root is not None:
        walk(root, frozenset())
    rows_self = sorted(self_t.items(), key=lambda kv: -kv[1])
    rows_self = [r for r in rows_self if not r[0].startswith("[")][:top]
    rows_incl = sorted(((k, v) for k, v in incl.items() if "sosdyn/" in k), key=lambda kv: -kv[1])[:top]
    out = {"tool": "pyinstrument", "total_s": total,
           "self": [{"function": k, "seconds": v, "share": v / total if total else 0} for k, v in rows_self],
           "inclusive_sosdyn": [{"function": k, "seconds": v, "share": v / total if total else 0}
                                for k, v in rows_incl]}
    return result, out


def _short_path(path) -> str:
    path = str(path or "")
    for marker in ("site-packages/", "/work/main/"):
        if marker in path:
            return path.split(marker, 1)[1]
    return path.rsplit("/", 2)[-1] if "/" in path else path


def _cprofile_call(fn, top):
    import cProfile
    import pstats
    pr = cProfile.Profile()
    t0 = now()
    pr.enable()
    try:
        result = fn()
    finally:
        pr.disable()
    total = now() - t0
    stats = pstats.Stats(pr, stream=io.StringIO())
    rows = []
    for (file, line, func), (_cc, _nc, tt, ct, _callers) in stats.stats.items():
        rows.append((f"{func} ({_short_path(file)}:{line})", tt, ct))
    rows_self = sorted(rows, key=lambda r: -r[1])[:top]
    rows_incl = sorted((r for r in rows if "sosdyn/" in r[0]), key=lambda r: -r[2])[:top]
    return result, {"tool": "cProfile", "total_s": total,
                    "self": [{"function": k, "seconds": s, "share": s / total} for k, s, _ in rows_self],
                    "inclusive_sosdyn": [{"function": k, "seconds": c, "share": c / total}
                                         for k, _, c in rows_incl]}


def profile_markdown(prof: dict, top=10) -> str:
    lines = [f"Profiler: {prof['tool']}, {fmt_s(prof['total_s'])} sampled.", "",
             "Top functions by own (self) time:", "",
             md_table(["function", "self", "share"],
                      [[f"`{r['function']}`", fmt_s(r["seconds"]), f"{100 * r['share']:.1f} %"]
                       for r in prof["self"][:top]]),
             "", "Top sosdyn functions by inclusive time (with callees):", "",
             md_table(["function", "total", "share"],
                      [[f"`{r['function']}`", fmt_s(r["seconds"]), f"{100 * r['share']:.1f} %"]
                       for r in prof["inclusive_sosdyn"][:top]])]
    return "\n".join(lines)

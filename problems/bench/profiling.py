"""Profiles of slow configurations: pyinstrument (cProfile as fallback), as Markdown."""
from __future__ import annotations

import cProfile
import io
import pstats
from pathlib import Path

from .timing import fmt_s, md_table, now


def profile_call(fn, top=15, interval=0.001):
    """Run ``fn`` under pyinstrument (cProfile as fallback); return (result, profile dict).

    The profile dict lists the functions with the largest *self* time (own code, not
    callees) and the largest *total* time among sosdyn functions, each with its share.
    """
    try:
        from pyinstrument import Profiler   # optional (the bench extra); cProfile without it
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


ROOT = str(Path(__file__).resolve().parents[2]) + "/"     # this checkout (a worktree is not /work/main)


def _short_path(path) -> str:
    """The file's path from site-packages/ or from the checkout's root (``sosdyn/...``), else its name."""
    path = str(path or "")
    if path.startswith(ROOT):
        return path[len(ROOT):]
    for marker in ("site-packages/", "/work/main/"):
        if marker in path:
            return path.split(marker, 1)[1]
    return path.rsplit("/", 2)[-1] if "/" in path else path


def _cprofile_call(fn, top):
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

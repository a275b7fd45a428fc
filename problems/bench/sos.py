"""``python -m problems bench-sos``: the SOS layer on known-answer and dense problems.

For every problem: build / canonicalise / solve seconds for the ``direct`` and ``cvxpy`` back ends,
the SDP sizes, the same problem in SumOfSquares.py (sympy + picos, solved by CVXOPT: the only SDP
solver picos finds here) and in Drake (pydrake, solved by Clarabel as ours; :mod:`.drake_problems`)
with ratios (against Drake with our stages split as Drake's are, :func:`.sos_split.like_drake`, and
on the problems Drake solves in under 2 ms the floor of a sosdyn solve, :func:`.sos_split.floor`),
the re-solve overhead of the compiled problem (``con.update(p)`` + solve minus the solver's own
time), the sparsity rows (chained Rosenbrock / Wood, :mod:`.sparse_problems`) and the sparse
scaling rows to n = 1000 (:mod:`.sparse_scaling`).
Writes ``reports/bench/sos.json`` and ``sos.md`` (:mod:`.sos_report`).

Options: ``--quick`` (small problems, few repetitions: the smoke test), ``--no-theirs``,
``--no-drake``, ``--no-sparse``, ``--sparse-budget SECONDS``, ``--out DIR``.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import traceback
import warnings
from importlib import metadata
from pathlib import Path

import numpy as np

from ..settings import BENCH
from . import drake_problems, sos_problems, sparse_problems, sparse_scaling
from .catalog import problems
from .cdsp_problems import cdsp_fields
from .profiling import profile_call
from .sos_report import markdown
from .sos_split import FLOOR_BELOW_S, build_split, floor, like_drake
from .timing import environment, fmt_s, median, now, write_json

BACKENDS = ("direct", "cvxpy")
TARGETS = {"build_share_of_solve": 0.10, "build_share_min_solve_s": 1.0, "resolve_overhead_s": 5e-3,
           "build_speedup_vs_sumofsquares": 50.0, "total_vs_drake": 1.0}


def reps_for(quick, budget_s=0.5, cap=30):
    """How many fresh runs a measurement takes, given the seconds of one run and the seconds
    spent so far: one in quick mode or above 2 s, two above 0.5 s, else repeat until
    ``budget_s`` is spent (at least 3, at most ``cap``), so millisecond builds are medians of
    many samples rather than one noisy one."""
    def count(per_run_s, elapsed_s):
        if quick or per_run_s > 2.0:
            return 1
        if per_run_s > 0.5:
            return 2
        return cap if elapsed_s < budget_s else 3
    return count


def run_ours(p, backend, quick):
    """Median build / canonicalise / solve of fresh builds of problem ``p`` with ``backend``."""
    runs, elapsed, reps = [], 0.0, reps_for(quick)
    while True:
        t0 = now()
        prog, _ = p.ours()
        build = now() - t0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = now()
            sol = prog.solve(backend=backend)
            wall = now() - t0
        own = sol.info.get("solver_own_seconds", sol.timings["solve"])
        verify = sol.timings.get("verify", 0.0)
        runs.append({"build": build, "build_program": sol.timings["build"],
                     "canonicalize": sol.timings["canonicalize"], "solve": sol.timings["solve"],
                     "solve_wall": wall, "verify": verify, "solver_own": own,
                     "canonicalize_like_drake": wall - verify - own,
                     "status": sol.status, "iterations": sol.info.get("iterations")})
        elapsed += build + sol.timings["canonicalize"] + sol.timings["solve"]
        if len(runs) >= reps(elapsed / len(runs), elapsed):
            break
    out = {k: median([r[k] for r in runs]) for k in ("build", "build_program", "canonicalize", "solve", "solve_wall",
                                                     "verify", "solver_own", "canonicalize_like_drake")}
    out["build_min"] = min(r["build"] for r in runs)
    out.update(status=runs[-1]["status"], iterations=runs[-1]["iterations"], repetitions=len(runs),
               sizes=prog.compile().sizes())
    if backend == "direct" and sol.status in ("optimal", "optimal_inaccurate"):
        rep = sol.verify()
        out["verified"] = bool(rep.passed)
        try:
            out["objective"] = float(sol.objective) if prog.objective else None
        except Exception:  # noqa: BLE001 -- e.g. inaccurate and failing the check
            out["objective"] = None
    return out


def run_resolve(p, backend, quick, first_solve_s):
    """Re-solve overhead: con.update(new numbers) + solve wall time minus the solver's own time."""
    if p.resolve is None:
        return None
    if first_solve_s > 2.0:
        return {"skipped": f"solve takes {first_solve_s:.1f} s; overhead measured on the smaller problems"}
    prog, ctx = p.ours()
    prog.solve(backend=backend)
    rng = np.random.default_rng(0)
    reps = 3 if quick else max(5, min(25, int(2.0 / max(first_solve_s, 1e-4))))
    over, update, total, solver, statuses = [], [], [], [], []
    for _ in range(reps):
        run = p.resolve(prog, ctx, rng)           # new polynomials prepared outside the timing
        t0 = now()
        run()
        t1 = now()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sol = prog.solve(backend=backend)
        t2 = now()
        update.append(t1 - t0)
        total.append(t2 - t0)
        solver.append(sol.timings["solve"])
        over.append(t2 - t0 - sol.timings["solve"])
        statuses.append(sol.status)
    return {"overhead": median(over), "update": median(update), "total": median(total),
            "solver": median(solver), "repetitions": reps, "statuses": sorted(set(statuses)),
            "overhead_min": float(np.min(over)), "overhead_max": float(np.max(over))}


def run_theirs(p, quick):
    if p.theirs is None:
        return None
    try:
        sos_problems.SPARSE[0] = True
        try:
            p.theirs()
        except ValueError:                   # its Newton-polytope hull needs full-dimensional support
            sos_problems.SPARSE[0] = False
        import picos  # optional (the bench extra): only when comparing with SumOfSquares.py
        runs, elapsed, reps = [], 0.0, reps_for(quick)
        while True:
            t0 = now()
            prob = p.theirs()
            build = now() - t0
            t0 = now()
            sol = prob.solve(solver="cvxopt", primals=None, duals=None, verbosity=0)
            wall = now() - t0
            search = float(getattr(sol, "searchTime", float("nan")))
            runs.append({"build": build, "solve": search, "canonicalize": wall - search,
                         "status": f"{sol.claimedStatus}/{sol.problemStatus}"})
            elapsed += build + wall
            if len(runs) >= reps(elapsed / len(runs), elapsed):
                break
        out = {k: median([r[k] for r in runs]) for k in ("build", "canonicalize", "solve")}
        out["build_min"] = min(r["build"] for r in runs)
        out.update(status=runs[-1]["status"], repetitions=len(runs), solver="cvxopt",
                   newton_reduction=sos_problems.SPARSE[0],
                   picos=picos.__version__, constraints=len(prob.constraints))
        return out
    except Exception as exc:  # noqa: BLE001 -- report, keep benchmarking
        return {"error": f"{type(exc).__name__}: {exc}", "trace": traceback.format_exc(limit=3)}
    finally:
        sos_problems.SPARSE[0] = True


def measure(p, args, drake_ok) -> dict:
    """Every measurement of one problem: both back ends, re-solve, SumOfSquares.py, Drake, ratios."""
    t0 = time.perf_counter()
    entry = {"name": p.name, "group": p.group, "expect": p.expect, "params": p.params or {}}
    for b in BACKENDS:
        entry[b] = run_ours(p, b, args.quick)
    first = entry["direct"]["solve"]
    entry["resolve"] = {b: run_resolve(p, b, args.quick, first) for b in BACKENDS}
    entry["sumofsquares"] = None if args.no_theirs else run_theirs(p, args.quick)
    entry["drake"] = drake_problems.run_drake(p, reps_for(args.quick)) if drake_ok else None
    d, th, dk = entry["direct"], entry["sumofsquares"], entry["drake"]
    ratios = {"cvxpy_over_direct_total": total(entry["cvxpy"]) / total(d),
              "cvxpy_over_direct_canonicalize": entry["cvxpy"]["canonicalize"] / d["canonicalize"]}
    if th and "error" not in th:
        ratios["build_theirs_over_ours"] = th["build_min"] / d["build_min"]     # fastest of each: least load noise
        ratios["build_theirs_over_ours_median"] = th["build"] / d["build"]
        ratios["build_canon_theirs_over_ours"] = (th["build"] + th["canonicalize"]) / (d["build"] + d["canonicalize"])
        ratios["solve_theirs_over_ours"] = th["solve"] / d["solve"] if d["solve"] > 0 else None
    if dk and "build" in dk:          # Drake / ours: above 1 ours is faster; stages as Drake's are split
        ours = like_drake(d)
        dk["ratios"] = {k: dk[k] / ours[k] if ours[k] > 0 else None for k in ("build", "canonicalize", "solve")}
        dk["ratios"]["total"] = total(dk) / total(ours)
        if total(dk) < FLOOR_BELOW_S:
            entry["floor"] = floor(p, 5 if args.quick else 200)
    ratios["build_canon_over_solve"] = (d["build"] + d["canonicalize"]) / d["solve"] if d["solve"] > 0 else None
    entry["ratios"] = ratios
    entry["status_ok"] = (p.expect == "any" or d["status"] == p.expect
                          or (p.expect == "optimal" and d["status"] == "optimal_inaccurate" and d.get("verified")))
    print(f"[bench-sos] {p.name:45s} {d['status']:>18s} build {fmt_s(d['build']):>9s} canon "
          f"{fmt_s(d['canonicalize']):>9s} solve {fmt_s(d['solve']):>9s}"
          + (f"  theirs build {fmt_s(th['build'])}" if th and 'error' not in th else
             (f"  theirs: {th['error'][:60]}" if th else ""))
          + (f"  Drake/ours total {dk['ratios']['total']:.2f}x" if dk and "ratios" in dk else "")
          + f"  ({time.perf_counter() - t0:.1f} s)", flush=True)
    return entry


def total(d) -> float:
    """Build + canonicalise + solve seconds of one measurement."""
    return d["build"] + d["canonicalize"] + d["solve"]


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m problems bench-sos")
    ap.add_argument("--quick", action="store_true", help="small sizes, one repetition (smoke test)")
    ap.add_argument("--no-theirs", action="store_true", help="skip SumOfSquares.py")
    ap.add_argument("--no-drake", action="store_true", help="skip Drake (skipped anyway when not installed)")
    ap.add_argument("--no-sparse", action="store_true", help="skip the chained Rosenbrock / Wood / scaling rows")
    ap.add_argument("--sparse-budget", type=float, default=None,
                    help="wall-time budget of one sparsity row, seconds (default 120, quick 30)")
    ap.add_argument("--out", default=str(BENCH))
    args = ap.parse_args(argv)
    out_dir = Path(args.out)
    t_start = now()
    load_start = os.getloadavg()[0]
    drake_ok = not args.no_drake and drake_problems.available() is not None

    dense_ns = (2, 3) if args.quick else (2, 3, 4, 5, 6)
    probs = problems(quick=args.quick, dense_ns=dense_ns)
    if args.quick:
        keep = {"quartic form", "Motzkin M", "SOS matrix", "probability bound (1/37)"}
        probs = [p for p in probs if p.name in keep or p.group in ("dense", "cdsp")]
    cdsp_fields()                   # fit the LASA model once, outside every timing
    for p in probs[:3]:             # warm-up: imports, first-call caches (all libraries)
        p.ours()[0].solve()
        p.ours()[0].solve(backend="cvxpy")
        if not args.no_theirs:
            run_theirs(p, quick=True)
        if drake_ok:
            drake_problems.run_drake(p, reps_for(True))

    rows = [measure(p, args, drake_ok) for p in probs]
    env = environment()
    env["load_average_start"], env["load_average_end"] = load_start, os.getloadavg()[0]
    env["drake"] = _version("drake") if drake_ok else None
    result = {"benchmark": "bench-sos", "quick": args.quick, "environment": env,
              "targets": TARGETS, "problems": rows}
    result["summary"] = summarize(rows)
    by_name = {p.name: p for p in probs}
    result["build_split"] = None        # the one-polynomial problem with the smallest speed-up
    for _, name in sorted((r["ratios"]["build_theirs_over_ours"], r["name"]) for r in rows
                          if r["ratios"].get("build_theirs_over_ours")):
        result["build_split"] = build_split(by_name[name], 5 if args.quick else 50, drake_ok)
        if result["build_split"]:
            break
    budget = args.sparse_budget or (30.0 if args.quick else 120.0)
    result["sparse_budget_s"] = budget
    result["sparse"] = None if args.no_sparse else sparse_problems.run_rows((4,) if args.quick else
                                                                           sparse_problems.NS, budget)
    result["summary"]["sparse_speedups"] = sparse_problems.speedups(result["sparse"] or [])
    result["sparse_scaling"] = None if args.no_sparse else sparse_scaling.run_scaling((40, 100) if args.quick else
                                                                                      sparse_scaling.NS)
    result["summary"]["sparse_scaling_targets"] = sparse_scaling.targets(result["sparse_scaling"] or [])
    result["profiles"] = profiles(probs, result["summary"], args.quick)
    result["elapsed_s"] = now() - t_start
    write_json(out_dir / "sos.json", result)
    (out_dir / "sos.md").write_text(markdown(result))
    print(f"[bench-sos] wrote {out_dir / 'sos.json'} and {out_dir / 'sos.md'} in {result['elapsed_s']:.0f} s")
    return 0


def _version(dist) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def profiles(probs, summary, quick):
    """Where the time goes for the missed targets: the build of the problem with the smallest
    speed-up over SumOfSquares.py, and the re-solve of the problem with the largest overhead."""
    out = []
    by_name = {p.name: p for p in probs}
    sp = summary["build_speedup"]
    if sp.get("met") is False or quick:
        p = by_name[sp["min_problem"]]
        reps = 20 if quick else 200

        def builds():
            for _ in range(reps):
                p.ours()
        _, prof = profile_call(builds)
        prof["title"] = f"build of '{p.name}' ×{reps} (smallest speed-up over SumOfSquares.py)"
        out.append(prof)
    rs = summary["resolve"]
    if rs["problems"] and (rs.get("met") is False or quick):
        worst = max(rs["problems"], key=lambda x: x["overhead"])
        p = by_name[worst["name"]]
        prog, ctx = p.ours()
        prog.solve()
        rng = np.random.default_rng(1)
        runs = [p.resolve(prog, ctx, rng) for _ in range(3 if quick else 20)]

        def resolves():
            for run in runs:
                run()
                prog.solve()
        _, prof = profile_call(resolves)
        prof["title"] = f"re-solve of '{p.name}' ×{len(runs)} (update + solve, direct; largest overhead)"
        out.append(prof)
    return out


def _gmean(xs):
    xs = [x for x in xs if x is not None and np.isfinite(x) and x > 0]
    return float(np.exp(np.mean(np.log(xs)))) if xs else None


def summarize(rows) -> dict:
    s = {}
    big = [r for r in rows if r["direct"]["solve"] >= TARGETS["build_share_min_solve_s"]]
    s["build_share"] = {"problems": [{"name": r["name"], "solve": r["direct"]["solve"],
                                      "share": r["ratios"]["build_canon_over_solve"]} for r in big]}
    s["build_share"]["met"] = all(x["share"] <= TARGETS["build_share_of_solve"] for x in s["build_share"]["problems"]) \
        if big else None
    res = [(r["name"], r["resolve"]["direct"]) for r in rows
           if r["resolve"]["direct"] and "overhead" in r["resolve"]["direct"]]
    s["resolve"] = {"problems": [{"name": n, "overhead": v["overhead"], "update": v["update"]} for n, v in res],
                    "max_overhead": max((v["overhead"] for _, v in res), default=None)}
    s["resolve"]["met"] = (s["resolve"]["max_overhead"] <= TARGETS["resolve_overhead_s"]) if res else None
    sp = [(r["name"], r["ratios"].get("build_theirs_over_ours")) for r in rows]
    sp = [(n, v) for n, v in sp if v]
    s["build_speedup"] = {"geomean": _gmean([v for _, v in sp]), "min": min((v for _, v in sp), default=None),
                          "min_problem": min(sp, key=lambda t: t[1])[0] if sp else None,
                          "max": max((v for _, v in sp), default=None)}
    s["build_speedup"]["met"] = (s["build_speedup"]["min"] >= TARGETS["build_speedup_vs_sumofsquares"]) if sp else None
    s["build_speedup"]["met_geomean"] = (s["build_speedup"]["geomean"] >= TARGETS["build_speedup_vs_sumofsquares"]) \
        if sp else None
    s["solve_ratio_theirs_over_ours_geomean"] = _gmean([r["ratios"].get("solve_theirs_over_ours") for r in rows])
    s["cvxpy_over_direct_total_geomean"] = _gmean([r["ratios"]["cvxpy_over_direct_total"] for r in rows])
    s["statuses_as_expected"] = all(r["status_ok"] for r in rows)
    dk = [(r["name"], r["drake"]["ratios"]["total"]) for r in rows if r.get("drake") and "ratios" in r["drake"]]
    s["drake"] = {"compared": len(dk), "wins": sum(v >= 1 for _, v in dk), "geomean": _gmean([v for _, v in dk]),
                  "min": min((v for _, v in dk), default=None), "max": max((v for _, v in dk), default=None),
                  "min_problem": min(dk, key=lambda t: t[1])[0] if dk else None,
                  "losses": [{"name": n, "drake_over_ours_total": v} for n, v in dk if v < 1]}
    s["drake"]["met"] = all(v >= TARGETS["total_vs_drake"] for _, v in dk) if dk else None
    return s


if __name__ == "__main__":
    sys.exit(main())

"""``python -m problems bench-sos``: the SOS layer on known-answer and dense problems.

For every problem: build / canonicalise / solve seconds for the ``direct`` and ``cvxpy`` back ends,
the SDP sizes, the same problem in SumOfSquares.py (sympy + picos, solved by CVXOPT: the only SDP
solver picos finds here) with ratios, and the re-solve overhead of the compiled problem
(``con.update(p)`` + solve minus the solver's own time). Writes ``reports/bench/sos.json`` and
``sos.md``.

Options: ``--quick`` (small problems, few repetitions: the smoke test), ``--no-theirs``,
``--out DIR``.
"""
from __future__ import annotations

import argparse
import sys
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

from ..settings import BENCH
from . import sos_problems
from .catalog import problems
from .cdsp_problems import cdsp_fields
from .profiling import profile_call, profile_markdown
from .timing import environment, fmt_ratio, fmt_s, md_table, median, now, verdict, write_json

BACKENDS = ("direct", "cvxpy")
TARGETS = {"build_share_of_solve": 0.10, "build_share_min_solve_s": 1.0, "resolve_overhead_s": 5e-3,
           "build_speedup_vs_sumofsquares": 50.0}


def _reps(seconds, quick, cap=5):
    if quick:
        return 1
    return 1 if seconds > 2.0 else (2 if seconds > 0.5 else cap)


def run_ours(p, backend, quick):
    """Median build / canonicalise / solve of fresh builds of problem ``p`` with ``backend``."""
    runs = []
    while True:
        t0 = now()
        prog, _ = p.ours()
        build = now() - t0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sol = prog.solve(backend=backend)
        runs.append({"build": build, "build_program": sol.timings["build"],
                     "canonicalize": sol.timings["canonicalize"], "solve": sol.timings["solve"],
                     "status": sol.status, "iterations": sol.info.get("iterations")})
        if len(runs) >= _reps(build + sol.timings["solve"], quick):
            break
    out = {k: median([r[k] for r in runs]) for k in ("build", "build_program", "canonicalize", "solve")}
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
        import picos   # optional (the bench extra): only when comparing with SumOfSquares.py
        runs = []
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
            if len(runs) >= _reps(build + wall, quick, cap=3):
                break
        out = {k: median([r[k] for r in runs]) for k in ("build", "canonicalize", "solve")}
        out.update(status=runs[-1]["status"], repetitions=len(runs), solver="cvxopt",
                   newton_reduction=sos_problems.SPARSE[0],
                   picos=picos.__version__, constraints=len(prob.constraints))
        return out
    except Exception as exc:  # noqa: BLE001 -- report, keep benchmarking
        return {"error": f"{type(exc).__name__}: {exc}", "trace": traceback.format_exc(limit=3)}
    finally:
        sos_problems.SPARSE[0] = True


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m problems bench-sos")
    ap.add_argument("--quick", action="store_true", help="small sizes, one repetition (smoke test)")
    ap.add_argument("--no-theirs", action="store_true", help="skip SumOfSquares.py")
    ap.add_argument("--out", default=str(BENCH))
    args = ap.parse_args(argv)
    out_dir = Path(args.out)
    t_start = now()

    dense_ns = (2, 3) if args.quick else (2, 3, 4, 5, 6)
    probs = problems(quick=args.quick, dense_ns=dense_ns)
    if args.quick:
        keep = {"quartic form", "Motzkin M", "SOS matrix", "probability bound (1/37)"}
        probs = [p for p in probs if p.name in keep or p.group in ("dense", "cdsp")]
    cdsp_fields()                   # fit the LASA model once, outside every timing
    for p in probs[:3]:             # warm-up: imports, first-call caches (both libraries)
        p.ours()[0].solve()
        p.ours()[0].solve(backend="cvxpy")
        if not args.no_theirs:
            run_theirs(p, quick=True)

    rows = []
    for p in probs:
        t0 = time.perf_counter()
        entry = {"name": p.name, "group": p.group, "expect": p.expect, "params": p.params or {}}
        for b in BACKENDS:
            entry[b] = run_ours(p, b, args.quick)
        first = entry["direct"]["solve"]
        entry["resolve"] = {b: run_resolve(p, b, args.quick, first) for b in BACKENDS}
        entry["sumofsquares"] = None if args.no_theirs else run_theirs(p, args.quick)
        d, th = entry["direct"], entry["sumofsquares"]
        ratios = {"cvxpy_over_direct_total": (sum(entry["cvxpy"][k] for k in ("build", "canonicalize", "solve"))
                                              / sum(d[k] for k in ("build", "canonicalize", "solve"))),
                  "cvxpy_over_direct_canonicalize": entry["cvxpy"]["canonicalize"] / d["canonicalize"]}
        if th and "error" not in th:
            ratios["build_theirs_over_ours"] = th["build"] / d["build"]
            ratios["build_canon_theirs_over_ours"] = (th["build"] + th["canonicalize"]) / (d["build"] + d["canonicalize"])
            ratios["solve_theirs_over_ours"] = th["solve"] / d["solve"] if d["solve"] > 0 else None
        ratios["build_canon_over_solve"] = (d["build"] + d["canonicalize"]) / d["solve"] if d["solve"] > 0 else None
        entry["ratios"] = ratios
        entry["status_ok"] = (p.expect == "any" or d["status"] == p.expect
                              or (p.expect == "optimal" and d["status"] == "optimal_inaccurate" and d.get("verified")))
        rows.append(entry)
        print(f"[bench-sos] {p.name:45s} {d['status']:>18s} build {fmt_s(d['build']):>9s} canon "
              f"{fmt_s(d['canonicalize']):>9s} solve {fmt_s(d['solve']):>9s}"
              + (f"  theirs build {fmt_s(th['build'])}" if th and 'error' not in th else
                 (f"  theirs: {th['error'][:60]}" if th else ""))
              + f"  ({time.perf_counter() - t0:.1f} s)", flush=True)

    result = {"benchmark": "bench-sos", "quick": args.quick, "environment": environment(),
              "targets": TARGETS, "problems": rows}
    result["summary"] = summarize(rows)
    result["profiles"] = profiles(probs, result["summary"], args.quick)
    result["elapsed_s"] = now() - t_start
    write_json(out_dir / "sos.json", result)
    (out_dir / "sos.md").write_text(markdown(result))
    print(f"[bench-sos] wrote {out_dir / 'sos.json'} and {out_dir / 'sos.md'} in {result['elapsed_s']:.0f} s")
    return 0


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
    return s


def markdown(res) -> str:
    rows, s = res["problems"], res["summary"]
    L = ["# SOS layer benchmark (`make bench-sos`)", "",
         "All numbers from one run on this machine "
         f"({res['environment'].get('processor')}, {res['environment'].get('cpus')} CPUs, Python "
         f"{res['environment']['python']}, Clarabel {res['environment']['clarabel']}, cvxpy "
         f"{res['environment']['cvxpy']}); ratios are the headline, seconds are secondary. "
         "Build = wall time from plain numbers to a program with all constraints (polynomial arithmetic, "
         "Newton polytope, Gram matching); canonicalise = conic assembly (direct) or conic assembly + cvxpy "
         "compilation (cvxpy); solve = the solver's own time. SumOfSquares.py: build = sympy expression "
         "to picos problem with all constraints; canonicalise = picos solve wall time minus the solver's "
         "search time; its solver is CVXOPT (the only SDP solver picos finds here; Clarabel is not a picos "
         "back end), so the solve ratio compares solvers, not formulations.", "",
         "## Targets", ""]
    bs = s["build_share"]
    share_txt = ", ".join(f"{x['name']}: {100 * x['share']:.2f} % of {fmt_s(x['solve'])}" for x in bs["problems"])
    rs = s["resolve"]
    worst = max(rs["problems"], key=lambda x: x["overhead"]) if rs["problems"] else None
    sp = s["build_speedup"]
    L += [md_table(["target", "result", "numbers"], [
        ["build + canonicalise ≤ 10 % of solve (solves ≥ 1 s, direct)", verdict(bs["met"]), share_txt or "no solve ≥ 1 s"],
        ["re-solve overhead ≤ 5 ms (update + solve − solver, direct, median)", verdict(rs["met"]),
         f"max {fmt_s(rs['max_overhead'])} ({worst['name']})" if worst else "–"],
        ["build ≥ 50× faster than SumOfSquares.py (every problem)", verdict(sp["met"]),
         f"min {fmt_ratio(sp['min'])} ({sp['min_problem']}), geometric mean {fmt_ratio(sp['geomean'])}, "
         f"max {fmt_ratio(sp['max'])}" if sp["min"] else "–"],
    ]), "",
        f"Other ratios: cvxpy / direct total time, geometric mean {fmt_ratio(s['cvxpy_over_direct_total_geomean'])}; "
        f"SumOfSquares (CVXOPT) / sosdyn (Clarabel) solver time, geometric mean "
        f"{fmt_ratio(s['solve_ratio_theirs_over_ours_geomean'])}. "
        f"Statuses as known: {'yes' if s['statuses_as_expected'] else 'NO (see table)'}.", "",
        "## Ratios per problem", "",
        md_table(["problem", "status (direct)", "build+canon / solve", "cvxpy / direct (total)",
                  "SoS.py / ours build", "SoS.py / ours build+canon", "SoS.py / ours solve"],
                 [[r["name"], r["direct"]["status"] + ("" if r["status_ok"] else " ⚠ expected " + r["expect"]),
                   f"{100 * r['ratios']['build_canon_over_solve']:.1f} %" if r["ratios"]["build_canon_over_solve"] else "–",
                   fmt_ratio(r["ratios"]["cvxpy_over_direct_total"]),
                   fmt_ratio(r["ratios"].get("build_theirs_over_ours")),
                   fmt_ratio(r["ratios"].get("build_canon_theirs_over_ours")),
                   fmt_ratio(r["ratios"].get("solve_theirs_over_ours"))] for r in rows]), "",
        "## Seconds and sizes", "",
        md_table(["problem", "SDP: vars / eqs / PSD blocks", "direct: build / canon / solve",
                  "cvxpy: build / canon / solve", "SumOfSquares.py: build / canon / solve (status)"],
                 [[r["name"],
                   f"{r['direct']['sizes']['variables']} / {r['direct']['sizes']['equalities']} / "
                   f"{_blocks(r['direct']['sizes']['psd_blocks'])}",
                   " / ".join(fmt_s(r["direct"][k]) for k in ("build", "canonicalize", "solve")),
                   " / ".join(fmt_s(r["cvxpy"][k]) for k in ("build", "canonicalize", "solve")),
                   (" / ".join(fmt_s(r["sumofsquares"][k]) for k in ("build", "canonicalize", "solve"))
                    + f" ({r['sumofsquares']['status']}"
                    + ("" if r["sumofsquares"].get("newton_reduction", True) else "; no Newton reduction: "
                       "its hull fails on this support") + ")") if r["sumofsquares"] and "error" not in r["sumofsquares"]
                   else (f"error: {r['sumofsquares']['error'][:80]}" if r["sumofsquares"] else "–")]
                  for r in rows]), "",
        "## Re-solve overhead (compile once, `con.update(p)`, solve again)", "",
        "New numbers with the same support are prepared outside the timing; overhead = "
        "wall(update + solve) − solver time, median over the repetitions.", "",
        md_table(["problem", "direct: overhead (update)", "cvxpy: overhead (update)", "solver time", "reps"],
                 [[r["name"],
                   _res(r["resolve"]["direct"]), _res(r["resolve"]["cvxpy"]),
                   fmt_s(r["resolve"]["direct"].get("solver")) if r["resolve"]["direct"] else "–",
                   r["resolve"]["direct"].get("repetitions", "–") if r["resolve"]["direct"] else "–"]
                  for r in rows if r["resolve"]["direct"]]), "",
        ]
    if res.get("profiles"):
        L += ["## Profiles of the missed targets", ""]
        for p in res["profiles"]:
            L += [f"### {p['title']}", "", profile_markdown(p), ""]
    L += [f"_Elapsed: {res.get('elapsed_s', 0):.0f} s._", ""]
    return "\n".join(L)


def _blocks(blocks):
    if not blocks:
        return "–"
    c = Counter(blocks)
    return " + ".join(f"{v}×{k}" if v > 1 else f"{k}" for k, v in sorted(c.items(), reverse=True))


def _res(v):
    if not v:
        return "–"
    if "skipped" in v:
        return "skipped (" + v["skipped"] + ")"
    return f"{fmt_s(v['overhead'])} ({fmt_s(v['update'])})"


if __name__ == "__main__":
    sys.exit(main())

"""``reports/bench/sos.md`` from the results of :mod:`.sos` (tables only, no measuring)."""
from __future__ import annotations

from collections import Counter

from .profiling import profile_markdown
from .sos_split import FLOOR_BELOW_S, like_drake
from .sparse_problems import markdown as sparse_markdown
from .sparse_scaling import markdown as scaling_markdown
from .timing import fmt_ratio, fmt_s, md_table, verdict


def _total(d) -> float:
    return d["build"] + d["canonicalize"] + d["solve"]


def markdown(res) -> str:
    rows, s = res["problems"], res["summary"]
    env = res["environment"]
    L = ["# SOS layer benchmark (`make bench-sos`)", "",
         ("All numbers from one run on this machine "
         f"({env.get('processor')}, {env.get('cpus')} CPUs, Python {env['python']}, Clarabel "
         f"{env['clarabel']}, cvxpy {env['cvxpy']}, Drake {env.get('drake') or 'not installed'}; 1-min load "
         f"average {env.get('load_average_start', float('nan')):.1f} at the start, "
         f"{env.get('load_average_end', float('nan')):.1f} at the end: other processes share the CPUs); ratios "
         "are the headline, seconds are secondary. Every time is the median over repetitions of fresh "
         "builds (small problems repeat until 0.5 s have been spent, at most 30 times, so a millisecond "
         "build is not one noisy sample); the build speed-up over SumOfSquares.py compares the fastest "
         "build of each library (the least disturbed by other processes; the median ratio is in sos.json). "
         "Build = wall time from plain numbers to a program with all constraints (polynomial arithmetic, "
         "Newton polytope, Gram matching); canonicalise = conic assembly (direct) or conic assembly + cvxpy "
         "compilation (cvxpy); solve = the solver's own time. SumOfSquares.py: build = sympy expression "
         "to picos problem with all constraints; canonicalise = picos solve wall time minus the solver's "
         "search time; its solver is CVXOPT (the only SDP solver picos finds here; Clarabel is not a picos "
         "back end), so the solve ratio compares solvers, not formulations. Drake (pydrake "
         "`MathematicalProgram`, `AddSosConstraint`, Newton-polytope basis, matrix SOS as yᵀG(x)y): build = "
         "plain numbers to program; canonicalise = `ClarabelSolver.Solve` wall time minus Clarabel's own "
         "time; solve = Clarabel's own time (same solver as ours, default settings)."), "",
         "## Targets", ""]
    bs, rs, sp, dk = s["build_share"], s["resolve"], s["build_speedup"], s["drake"]
    share_txt = ", ".join(f"{x['name']}: {100 * x['share']:.2f} % of {fmt_s(x['solve'])}" for x in bs["problems"])
    worst = max(rs["problems"], key=lambda x: x["overhead"]) if rs["problems"] else None
    L += [md_table(["target", "result", "numbers"], [
        ["build + canonicalise ≤ 10 % of solve (solves ≥ 1 s, direct)", verdict(bs["met"]), share_txt or "no solve ≥ 1 s"],
        ["re-solve overhead ≤ 5 ms (update + solve − solver, direct, median)", verdict(rs["met"]),
         f"max {fmt_s(rs['max_overhead'])} ({worst['name']})" if worst else "–"],
        ["build ≥ 50× faster than SumOfSquares.py (every problem)", verdict(sp["met"]),
         f"min {fmt_ratio(sp['min'])} ({sp['min_problem']}), geometric mean {fmt_ratio(sp['geomean'])}, "
         f"max {fmt_ratio(sp['max'])}" if sp["min"] else "–"],
        ["build + canonicalise + solve at least as fast as Drake (every problem, direct)", verdict(dk["met"]),
         f"Drake / ours total: min {fmt_ratio(dk['min'])} ({dk['min_problem']}), geometric mean "
         f"{fmt_ratio(dk['geomean'])}, max {fmt_ratio(dk['max'])}; ours faster on {dk['wins']} of "
         f"{dk['compared']}" if dk["min"] else "–"],
    ]), "",
        (f"Other ratios: cvxpy / direct total time, geometric mean {fmt_ratio(s['cvxpy_over_direct_total_geomean'])}; "
        f"SumOfSquares (CVXOPT) / sosdyn (Clarabel) solver time, geometric mean "
        f"{fmt_ratio(s['solve_ratio_theirs_over_ours_geomean'])}. "
        f"Statuses as known: {'yes' if s['statuses_as_expected'] else 'NO (see table)'}."), "",
        "## Ratios per problem", "",
        md_table(["problem", "status (direct)", "build+canon / solve", "cvxpy / direct (total)",
                  "SoS.py / ours build", "SoS.py / ours build+canon", "SoS.py / ours solve"],
                 [[r["name"], r["direct"]["status"] + ("" if r["status_ok"] else " ⚠ expected " + r["expect"]),
                   f"{100 * r['ratios']['build_canon_over_solve']:.1f} %" if r["ratios"]["build_canon_over_solve"] else "–",
                   fmt_ratio(r["ratios"]["cvxpy_over_direct_total"]),
                   fmt_ratio(r["ratios"].get("build_theirs_over_ours")),
                   fmt_ratio(r["ratios"].get("build_canon_theirs_over_ours")),
                   fmt_ratio(r["ratios"].get("solve_theirs_over_ours"))] for r in rows]), ""]
    L += drake_section(rows)
    L += floor_section(rows)
    L += build_split_section(res.get("build_split"))
    L += ["## Seconds and sizes", "",
          md_table(["problem", "SDP: vars / eqs / PSD blocks", "direct: build / canon / solve",
                    "cvxpy: build / canon / solve", "SumOfSquares.py: build / canon / solve (status)"],
                   [[r["name"],
                     (f"{r['direct']['sizes']['variables']} / {r['direct']['sizes']['equalities']} / "
                     f"{_blocks(r['direct']['sizes']['psd_blocks'])}"),
                     " / ".join(fmt_s(r["direct"][k]) for k in ("build", "canonicalize", "solve")),
                     " / ".join(fmt_s(r["cvxpy"][k]) for k in ("build", "canonicalize", "solve")),
                     _theirs(r["sumofsquares"])] for r in rows]), "",
          "## Re-solve overhead (compile once, `con.update(p)`, solve again)", "",
          ("New numbers with the same support are prepared outside the timing; overhead = "
          "wall(update + solve) − solver time, median over the repetitions."), "",
          md_table(["problem", "direct: overhead (update)", "cvxpy: overhead (update)", "solver time", "reps"],
                   [[r["name"], _res(r["resolve"]["direct"]), _res(r["resolve"]["cvxpy"]),
                     fmt_s(r["resolve"]["direct"].get("solver")) if r["resolve"]["direct"] else "–",
                     r["resolve"]["direct"].get("repetitions", "–") if r["resolve"]["direct"] else "–"]
                    for r in rows if r["resolve"]["direct"]]), ""]
    if res.get("sparse") is not None:
        L += sparse_markdown(res["sparse"], res["sparse_budget_s"])
    if res.get("sparse_scaling"):
        L += scaling_markdown(res["sparse_scaling"])
    if res.get("profiles"):
        L += ["## Profiles of the missed targets", ""]
        for p in res["profiles"]:
            L += [f"### {p['title']}", "", profile_markdown(p), ""]
    L += [f"_Elapsed: {res.get('elapsed_s', 0):.0f} s._", ""]
    return "\n".join(L)


def drake_section(rows) -> list:
    """Side by side with Drake: seconds, ratios (Drake / ours, > 1 means ours is faster), answers."""
    def cell(d):
        if d is None:
            return "–", "–", "–", "–", "–"
        if "skipped" in d or "error" in d:
            txt = d.get("skipped") or "error: " + d["error"][:80]
            return txt, "–", "–", "–", "–"
        return (" / ".join(fmt_s(d[k]) for k in ("build", "canonicalize", "solve")) + f" ({d['status']})",
                *(fmt_ratio(d["ratios"][k]) for k in ("build", "canonicalize", "solve", "total")))
    def ours(d):
        o = like_drake(d)
        return " / ".join(fmt_s(o[k]) for k in ("build", "canonicalize", "solve")) + f" ({fmt_s(o['verify'])})"
    body = [[r["name"], ours(r["direct"]), *cell(r.get("drake")), _same_answer(r)] for r in rows]
    return ["## Side by side with Drake (Clarabel in both)", "",
            ("Ratios are Drake / sosdyn (direct back end): above 1× sosdyn is faster. Total = build + "
            "canonicalise + solve, with the stages split the same way in both: solve = Clarabel's own time "
            "(its `solve_time`), canonicalise = the rest of the solve call (sosdyn: `prog.solve()` wall time "
            "minus Clarabel's own time and minus the independent check, so conic assembly, lowering, the "
            "Python → Clarabel call and reading the answer back are all in it). The independent check, which "
            "Drake does not do, is shown in brackets and is not in the total."), "",
            md_table(["problem", "sosdyn: build / canon / solve (check)", "Drake: build / canon / solve (status)",
                      "build", "canon", "solve", "total", "same answer"], body), ""]


def floor_section(rows) -> list:
    """The floor of the smallest problems: the Clarabel call from Python against Drake's total."""
    body = []
    for r in rows:
        f, dk = r.get("floor"), r.get("drake")
        if not f or not dk or "build" not in dk:
            continue
        o, drake_total = like_drake(r["direct"]), _total(r["drake"])
        ours_total = _total(o)
        body.append([r["name"], fmt_s(drake_total), fmt_s(ours_total), fmt_s(f["clarabel_call"]),
                     fmt_s(f["clarabel_own"]), fmt_s(ours_total - f["clarabel_call"]),
                     f"{100 * f['clarabel_call'] / drake_total:.0f} %", fmt_ratio(drake_total / ours_total)])
    if not body:
        return []
    return [f"## The floor on the smallest problems (Drake total below {fmt_s(FLOOR_BELOW_S)})", "",
            ("Clarabel call = `DefaultSolver(P, q, A, b, cones, settings).solve()` from Python on the finished "
            "scipy CSC matrices and cone list (median of 200 calls; the data conversion into Clarabel, its "
            "setup and its iterations), with Clarabel's own `solve_time` inside it. Everything else of sosdyn's "
            "total (build + canonicalise + solve as in the Drake table) is Python: polynomial arithmetic, "
            "Newton polytope, Gram matching, conic assembly, lowering, reading the answer back. The floor "
            "column is the share of Drake's total the Clarabel call alone takes: what is left of Drake's "
            "total for all of sosdyn's Python work."), "",
            md_table(["problem", "Drake total", "sosdyn total", "Clarabel call from Python",
                      "of which Clarabel's own", "sosdyn Python (total − call)", "call / Drake total",
                      "Drake / sosdyn total"], body), ""]


def _same_answer(r) -> str:
    d = r.get("drake")
    if not d or "status" not in d:
        return "–"
    ours, theirs = r["direct"]["status"], d["status"]
    if (ours in ("optimal", "optimal_inaccurate")) != (theirs == "optimal"):
        return f"no ({ours} vs {theirs})"
    a, b = r["direct"].get("objective"), d.get("objective")
    if a is not None and b is not None:                      # Drake minimises; a max is reported negated
        ok = min(abs(a - b), abs(a + b)) <= 1e-4 * (1 + abs(a))
        return "yes" if ok else f"no ({a:.6g} vs {b:.6g})"
    return "yes"


def build_split_section(split) -> list:
    """Where the build of the one-polynomial problem with the smallest speed-up goes, per library."""
    if not split:
        return []
    body = [[lib, stage, fmt_s(v["min"]), fmt_s(v["median"])] for lib, stages in split["stages"].items()
            for stage, v in stages.items()]
    return [f"## Build split of '{split['problem']}' (of the one-polynomial problems, the smallest build speed-up over SumOfSquares.py)", "",
            (f"{split['repetitions']} fresh builds each; the polynomial is the same expression in every library "
            "(sosdyn polynomials, sympy with `expand`, Drake symbolic expressions), then one SOS constraint "
            "with a Newton-polytope basis. sympy caches the expressions it builds, so repeated builds of the "
            "same polynomial cost less than a user's first one; the cache-cleared row shows the uncached cost."),
            "",
            md_table(["library", "stage", "min", "median"], body), ""]


def _theirs(t) -> str:
    if not t:
        return "–"
    if "error" in t:
        return f"error: {t['error'][:80]}"
    return (" / ".join(fmt_s(t[k]) for k in ("build", "canonicalize", "solve")) + f" ({t['status']}"
            + ("" if t.get("newton_reduction", True) else "; no Newton reduction: its hull fails on this support")
            + ")")


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

"""The Markdown summary of ``python -m problems bench`` (``reports/bench/summary.md``)."""
from __future__ import annotations

from .profiling import profile_markdown
from .scaling_n import markdown as scaling_n_markdown
from .timing import fmt_ratio, fmt_s, md_table, verdict


def _fit_row(f):
    return [f["shape"], f["K"], f["variant"], fmt_s(f["total"]), fmt_s(f["em"]), fmt_s(f["build"]),
            fmt_s(f["solve"]), fmt_s(f["steps"]), fmt_s(f["certify"]), fmt_s(f["verify"]), fmt_s(f["data"]),
            f"{f['sdp_solves']}", f"{100 * f['build'] / max(f['solve'], 1e-12):.0f} %"
            if f["solve"] > 0 else "–", "yes" if f["certified"] else "NO"]


def summary_markdown(res, out_dir) -> str:
    fits, sweeps, backends, targets = res["fits"], res["sweeps"], res["backends"], res["targets"]
    L = ["# Benchmarks (`make bench`, `make bench-sos`)", "",
         f"One run on this machine ({res['environment'].get('processor')}, {res['environment'].get('cpus')} CPUs, "
         f"Python {res['environment']['python']}, Clarabel {res['environment']['clarabel']}, cvxpy "
         f"{res['environment']['cvxpy']}). Ratios measured in this run are the headline; absolute seconds "
         "are secondary and machine dependent.", "", "## Headline", ""]
    # headline ratios
    tot = lambda key: sum(f[key] for f in fits)  # noqa: E731
    all_t = tot("total")
    if all_t > 0:
        shares = ", ".join(f"{lab} {100 * tot(k) / all_t:.0f} %" for k, lab in
                           (("em", "EM"), ("build", "SOS build"), ("solve", "solver"), ("steps", "other learning"),
                            ("certify", "certificate"), ("verify", "verify"), ("data", "data/other")))
        L.append(f"- Share of all per-shape fit time: {shares}.")
        L.append(f"- SOS build / solver time over all fits: {fmt_ratio(tot('build') / max(tot('solve'), 1e-12))}.")
    for b in backends:
        L.append(f"- Dynamics step re-solve ({b['shape']}, K={b['K']}, field degree {b['field_degree']}, metric "
                 f"degree {b['metric_degree']}): cvxpy / direct = {fmt_ratio(b['ratios']['cvxpy_over_direct_step'])} "
                 f"per step, {fmt_ratio(b['ratios']['cvxpy_over_direct_overhead'])} on the non-solver overhead.")
    if "samples" in sweeps:
        s = sweeps["samples"].get("slopes", {})
        L.append(f"- Samples sweep log-log slopes: EM {_f(s.get('EM'))}, SOS build {_f(s.get('build'))}, "
                 f"solver {_f(s.get('solver'))}, data compression {_f(s.get('data'))}, total {_f(s.get('total'))}.")
    sos = res.get("sos_summary")
    if sos:
        sp = sos["build_speedup"]
        L.append(f"- SOS layer vs SumOfSquares.py: build speed-up min {fmt_ratio(sp['min'])}, geometric mean "
                 f"{fmt_ratio(sp['geomean'])}, max {fmt_ratio(sp['max'])} (details in [sos.md](sos.md)).")
    L += ["", "## Targets", ""]
    lim = res["targets_def"]
    rows = [[f"linear fit (linear+ICA) ≤ {fmt_s(lim['linear_fit_s'])} per shape", verdict(targets["linear_fit"]["met"]),
             ", ".join(f"{k} {fmt_s(v)}" for k, v in targets["linear_fit"]["per_shape"].items())]]
    for key in ("paper_fit", "cubic_fit"):
        if targets[key]["per_shape"]:
            rows.append([f"{targets[key]['variant']} ≤ {fmt_s(lim[key + '_s'])} per shape", verdict(targets[key]["met"]),
                         ", ".join(f"{k} {fmt_s(v)}" for k, v in targets[key]["per_shape"].items())])
    ov = res.get("overhead")
    if ov:
        rows.append([f"default CDSP() ≤ {ov['target']:g}x its plain core (paper shapes, sum)", verdict(ov["met"]),
                     f"{fmt_ratio(ov['ratio'])} ({fmt_s(ov['default_s'])} / {fmt_s(ov['core_s'])} "
                     f"{ov.get('clock', 'wall time')}; candidates {fmt_ratio(ov['candidates_over_core'])}, choice "
                     f"{fmt_ratio(ov['choice_over_core'])} of the core in wall time)"])
    rows.append([f"re-solve overhead ≤ {fmt_s(lim['resolve_overhead_s'])} (dynamics step, direct: update + canonicalise)",
                 verdict(targets["resolve"]["met"]),
                 f"max {fmt_s(targets['resolve']['max_overhead_update_solve'])}; whole step minus solver "
                 f"(incl. contraction-matrix arithmetic) {fmt_s(targets['resolve']['max_overhead_full_step'])}"])
    rows += evaluator_rows(res.get("predict"), res.get("dtw"))
    if sos:
        rows.append(["SOS: build + canonicalise ≤ 10 % of solve (solves ≥ 1 s)", verdict(sos["build_share"]["met"]),
                     ", ".join(f"{x['name']} {100 * x['share']:.2f} %" for x in sos["build_share"]["problems"])])
        rows.append(["SOS: re-solve overhead ≤ 5 ms", verdict(sos["resolve"]["met"]),
                     f"max {fmt_s(sos['resolve']['max_overhead'])}"])
        rows.append(["SOS: build ≥ 50× faster than SumOfSquares.py", verdict(sos["build_speedup"]["met"]),
                     f"min {fmt_ratio(sos['build_speedup']['min'])} ({sos['build_speedup']['min_problem']}), "
                     f"geomean {fmt_ratio(sos['build_speedup']['geomean'])}"])
    L += [md_table(["target", "result", "numbers"], rows), ""]
    L += ["## Per-fit timings (paper shapes)", "",
          "From public timing data: build = the learning steps' SOS build + canonicalise and solve = "
          "their solver time (`Solution.timings`, as `model.history_` records them); steps = the rest "
          "of learning (contraction-matrix arithmetic); certify = the final certificate; data = "
          "least-squares compression and bookkeeping.", "",
          md_table(["shape", "K", "variant", "total", "EM", "build", "solve", "steps", "certify", "verify", "data",
                    "SDPs", "build/solve", "certified"], [_fit_row(f) for f in fits]), ""]
    L += ["## Scaling", ""]
    if res.get("scaling_n"):
        L += [scaling_n_markdown(res["scaling_n"], res["scaling_n"]["plot"])]
    paper_n = out_dir / "scaling_n_paper.md"        # the alternating learner (issue 14's first measurement)
    if paper_n.exists():
        L += [paper_n.read_text()]
    for name, sw in sweeps.items():
        rows = [[r["label"], fmt_s(r["total"]), fmt_s(r["em"]), fmt_s(r["build"]), fmt_s(r["solve"]),
                 fmt_s(r["steps"]), fmt_s(r["certify"]), fmt_s(r["verify"]), fmt_s(r["data"]), r["sdp_solves"]]
                for r in sw["rows"]]
        slopes = sw.get("slopes", {})
        L += [f"### {sw['xlabel']}", "", sw["note"] + ".", "",
              f"![{name}]({sw.get('plot', '')})", "",
              "log-log slopes: " + ", ".join(f"{k} {_f(v)}" for k, v in slopes.items()) + ".", "",
              md_table(["point", "total", "EM", "build", "solve", "steps", "certify", "verify", "data", "SDPs"],
                       rows), ""]
    L += ["## Back ends on the learner's dynamics step (re-solve path)", "",
          "The same DynamicsStep (built once) re-solved for metrics near the learned one; median over "
          "repetitions. overhead = the solve's recorded build (constraint update) + canonicalise "
          "(`Solution.timings`); whole "
          "step also includes the contraction-matrix polynomial arithmetic of `DynamicsStep.solve`.", "",
          md_table(["step", "SDP vars / eqs / PSD", "direct: step / solver / overhead",
                    "cvxpy: step / solver / overhead", "cvxpy / direct: step, overhead, solver"],
                   [[f"{b['shape']} K={b['K']} field {b['field_degree']} metric {b['metric_degree']}",
                     f"{b['direct']['sizes']['variables']} / {b['direct']['sizes']['equalities']} / "
                     f"{len(b['direct']['sizes']['psd_blocks'])} blocks (max {max(b['direct']['sizes']['psd_blocks'])})",
                     " / ".join(fmt_s(b["direct"][k]) for k in ("step_wall", "solver", "overhead_update_solve")),
                     " / ".join(fmt_s(b["cvxpy"][k]) for k in ("step_wall", "solver", "overhead_update_solve")),
                     ", ".join(fmt_ratio(b["ratios"][k]) for k in ("cvxpy_over_direct_step", "cvxpy_over_direct_overhead",
                                                                   "cvxpy_over_direct_solver"))]
                    for b in backends]), ""]
    if res.get("scaling_n") and not res["scaling_n"].get("preset"):
        L += [blockers_markdown(res["scaling_n"])]
    if res["profiles"]:
        L += ["## Profiles of the missed targets", ""]
        for p in res["profiles"]:
            L += [f"### {p['title']}", "", profile_markdown(p), ""]
    sos_md = out_dir / "sos.md"
    if sos_md.exists():
        text = sos_md.read_text()
        head = text.split("## Ratios per problem")[0].split("## Targets", 1)
        if len(head) == 2:
            L += ["## SOS layer (`make bench-sos`, full tables in [sos.md](sos.md))", "", head[1].strip(), ""]
    L.append(f"_Elapsed: {res.get('elapsed_s', 0):.0f} s._")
    return "\n".join(L) + "\n"


def evaluator_rows(pred: dict | None, dtw: dict | None) -> list[list[str]]:
    """Target rows of the one-state evaluator (``predict.json``) and of the DTW distance (``dtw.json``)."""
    rows = []
    if pred:
        per = [f"degree {r['field_degree']}, {r['warp_bumps']} bumps: {fmt_s(r['predictor_s'])} "
               f"({fmt_ratio(r['speedup'])} predict)" for r in pred["rows"]]
        rows.append([f"predictor() ≤ {fmt_s(pred['target_s'])} per state (K = 8, 2-D)",
                     verdict(all(r["within_target"] for r in pred["rows"])), "; ".join(per)])
        if "speedup_target" in pred:
            rows.append([f"predictor() ≥ {pred['speedup_target']:g}× faster than predict(x[None]) on one state",
                         verdict(all(r["speedup_met"] for r in pred["rows"])),
                         f"min {fmt_ratio(min(r['speedup'] for r in pred['rows']))}"])
    if dtw:
        rows.append([", ".join(f"DTW {r['points'][0]} × {r['points'][1]} ≤ {fmt_s(r['target_s'])}" for r in dtw["rows"]),
                     verdict(dtw["met"]), ", ".join(fmt_s(r["median_s"]) for r in dtw["rows"])])
    return rows


def blockers_markdown(scaling) -> str:
    """What bounds each missed n-scaling goal, from the scaling rows alone (per-SDP times and floors)."""
    g, rows = scaling["goals"], {r["n"]: r for r in scaling["rows"]}
    lo, hi = rows[g["ratio"]["n_min"]], rows[g["ratio"]["n_max"]]
    per = lambda r, key: r[key] / max(r["sdp_solves"], 1)  # noqa: E731
    table = [[f"n={r['n']}", r["sdp_solves"], fmt_s(per(r, "solve")), fmt_s(per(r, "build")),
              fmt_s(per(r, "sos_build")), fmt_s(r["solve_check"]), fmt_s(r["em"] + r["verify"])]
             for r in scaling["rows"]]
    floor = hi["solve"] / lo["total"]
    return "\n".join([
        "### What bounds the n-scaling goals (from the rows above)", "",
        f"- Ratio goal: the solver alone at n={hi['n']} takes {fmt_s(hi['solve'])} ({hi['sdp_solves']} SDPs), "
        f"{fmt_ratio(floor)} the whole n={lo['n']} fit ({fmt_s(lo['total'])}). With every non-solver cost at zero the "
        f"ratio would still be {fmt_ratio(floor)}; the goal (≤ 4×) needs fewer or smaller SDPs at large n, not a "
        "faster build.",
        f"- Build ≤ solve: at n={lo['n']} one SDP solves in {fmt_s(per(lo, 'solve'))} while its build share is "
        f"{fmt_s(per(lo, 'build'))} (SOS layer {fmt_s(per(lo, 'sos_build'))}, independent check "
        f"{fmt_s(lo['solve_check'])}); small SDPs solve in about a millisecond, so every fixed Python cost per step "
        "counts against this goal.", "",
        md_table(["n", "SDPs", "solve / SDP", "build / SDP", "SOS build / SDP", "check of one solve",
                  "EM + verify (once)"], table), ""])


def _f(v):
    return "–" if v is None else f"{v:.2f}"

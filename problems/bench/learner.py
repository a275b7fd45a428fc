"""``python -m problems bench``: where the CDSP learner spends its time.

* per-fit timings for the four paper shapes (BendedLine, DoubleBendedLine, Leaf_1, Leaf_2 with
  K = 6/7/6/6) and four variants: linear + ICA, the paper formulation (metric degree 2,
  alternating), cubic fields + degree-2 metric -- each the learner's core fit
  (one plain fit: ``sosdyn.lfd.fit.params.PLAIN``, no warp, no corrective refits) -- and the default's
  full fit, linear + ICA with its choice of warp (a fit per candidate);
* scaling sweeps (log-log plots): K, metric degree, field degree, number of demonstration
  samples; the default fit against the dimension n = 2..7 with the issue-14 goals (:mod:`.scaling_n`);
* the learner's dynamics step on the re-solve path, "direct" vs "cvxpy" back end;
* the default's overhead: ``CDSP()`` over its plain core on the paper's shapes (:mod:`.default_overhead`);
* a profile (pyinstrument) of every configuration that misses its target.

Writes ``reports/bench/{fits,scaling,scaling_n,backends,profiles}.json``, the plots ``reports/bench/scaling_*``
and ``reports/bench/summary.md`` (which also carries the headline of ``bench-sos`` when its
``sos.json`` exists). ``--quick``: tiny sizes (the smoke test).

Timing decomposition of one fit, from public timing data only (``model.timings_`` and the
``Solution.timings`` each convex step records in ``model.history_``; a missing one is an
error, never a silent 0): EM = GaussianMixture fit; build = the learner's SOS build +
canonicalise (``build_s`` of the steps); solve = the solver's own time (``solve_s``); steps =
the rest of the learning stage (contraction-matrix arithmetic, bookkeeping); certify = the
final SOS certificate; verify = the sampled independent check; data = the rest (least-squares
compression). A fit made of several fits (corrective refits, the default's choice of warp) is split
for the model it keeps; the other fits and the training rollouts are in data (``rounds`` counts the
corrective rounds).
"""
from __future__ import annotations

import argparse
import functools
import json
import sys
import warnings
from pathlib import Path

import numpy as np

from sosdyn.lfd import CDSP, load_lasa
from sosdyn.lfd.fit.params import PLAIN, PRESETS
from sosdyn.poly import monomials_up_to
from sosdyn.report.figures import save_figure, scaling_plot

from ..settings import BENCH, PAPER_SHAPES
from .learner_report import summary_markdown
from . import default_overhead, dtw, predict, scaling_n
from .profiling import profile_call
from .synthetic import demos as synth
from .timing import environment, fmt_s, median, now, timing, write_json

SHAPES = {s.name: s.K for s in PAPER_SHAPES}
CORE = PLAIN                              # the learner's core fit; the default adds its choice of warp
VARIANTS = {
    "linear+ICA": dict(CORE, solver_method="ica"),
    "paper (metric deg 2, alternating)": dict(CORE, metric_degree=2, solver_method="alternating"),
    "cubic + metric deg 2": {k: v for k, v in PRESETS["cubic"].items() if k != "n_components"},
    "default (linear+ICA, choice of warp: a fit per candidate)": dict(solver_method="ica"),
}
SWEEP_BASE = dict(CORE, solver_method="ica")   # the sweeps vary one setting of the default's core fit
TARGETS = {"linear_fit_s": 0.5, "paper_fit_s": 10.0, "cubic_fit_s": 3.0, "resolve_overhead_s": 2e-3}   # issue 14
PARTS = ("em", "data", "build", "solve", "steps", "certify", "verify")


def log(msg):
    print(f"[bench] {msg}", flush=True)


# ---------------------------------------------------------------------- one fit
def timed_fit(demos, **params) -> dict:
    """One CDSP fit, its time split by public timing data (module docstring)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = now()
        model = CDSP(**dict(params, allow_uncertified=True)).fit(demos)     # timed either way; reported
        wall = now() - t0
    T, hist = model.timings_, model.history_
    total, em, learn = (timing(T, k, "model.timings_") for k in ("total_s", "em_s", "learn_s"))
    certify, verify = timing(T, "certify_s", "model.timings_"), timing(T, "verify_s", "model.timings_")
    kept = getattr(model, "corrective_round_", 0)          # with corrective refits: the kept round's rows
    solves = [(i, row) for i, row in enumerate(hist) if "status" in row and row.get("round", kept) == kept]
    if not solves:
        raise KeyError("model.history_ records no solved step; the benchmark cannot split the time")
    build = sum(timing(row, "build_s", f"model.history_[{i}]") for i, row in solves)
    solve = sum(timing(row, "solve_s", f"model.history_[{i}]") for i, row in solves)
    rec = {"total": total, "wall": wall, "em": em, "verify": verify, "build": build, "solve": solve,
           "steps": learn - build - solve, "learn": learn, "certify": certify,
           "data": total - em - learn - certify - verify, "sdp_solves": len(solves) + 1,
           "final_cost": hist[-1]["cost"] if hist else None, "rounds": len({row.get("round", 0) for row in hist}),
           "certified": bool(model.certified_), "samples": int(sum(len(d.t) for d in demos)),
           "params": {k: v for k, v in params.items() if k != "progress"}}
    rec["sdp_path"] = build + solve + certify
    return rec


# ---------------------------------------------------------------------- per-shape fits
def run_shapes(quick):
    shapes = {"Leaf_1": 2} if quick else SHAPES
    variants = {"linear+ICA": VARIANTS["linear+ICA"]} if quick else VARIANTS
    out = []
    for shape, K in shapes.items():
        demos = load_lasa(shape)
        for vname, params in variants.items():
            kw = dict(params, n_components=K, random_state=0)
            if quick:
                kw.update(max_iter=2, verify_samples=500, max_samples=500)
            rec = timed_fit(demos, **kw)
            rec.update(shape=shape, K=K, variant=vname)
            out.append(rec)
            log(f"{shape:17s} K={K} {vname:34s} total {fmt_s(rec['total']):>8s} em {fmt_s(rec['em']):>8s} "
                f"build {fmt_s(rec['build']):>8s} certify {fmt_s(rec['certify']):>8s} solve "
                f"{fmt_s(rec['solve']):>8s} verify {fmt_s(rec['verify']):>8s} ({rec['sdp_solves']} SDPs)")
    return out


# ---------------------------------------------------------------------- sweeps
def run_sweeps(quick):
    leaf = load_lasa("Leaf_1")
    q = dict(max_iter=2, verify_samples=500) if quick else {}
    sweeps = {}

    def sweep(name, xlabel, points, note):
        rows = []
        for x, label, demos, params in points:
            rec = timed_fit(demos, random_state=0, **dict(params, **q))
            rec.update(x=x, label=label)
            rows.append(rec)
            log(f"sweep {name:8s} {label:>22s}: total {fmt_s(rec['total']):>8s} em {fmt_s(rec['em']):>8s} "
                f"sdp path {fmt_s(rec['sdp_path']):>8s} ({rec['sdp_solves']} SDPs)")
        sweeps[name] = {"xlabel": xlabel, "note": note, "rows": rows}

    Ks = (2, 3) if quick else (2, 3, 4, 6, 8, 11, 15)
    sweep("K", "number of Gaussians K", [(K, f"K={K}", leaf, dict(SWEEP_BASE, n_components=K)) for K in Ks],
          "Leaf_1, linear fields, constant metric, ICA: the default's core fit (one plain fit; K = 8 is the default)")
    mds = (0,) if quick else (0, 2, 4)
    sweep("metric", "metric monomials per entry (metric degree 0 / 2 / 4)",
          [(monomials_up_to(2, d).shape[0], f"metric degree {d}", leaf,
            dict(SWEEP_BASE, n_components=2 if quick else 6, metric_degree=d)) for d in mds],
          "Leaf_1, K = 6, linear fields, the default's core fit (ICA start; a polynomial metric adds the "
          "proximal alternation); x = monomials of M(z) per entry (1, 6, 15)")
    fds = (1,) if quick else (1, 3)
    sweep("field", "field degree", [(d, f"field degree {d}", leaf, dict(SWEEP_BASE, n_components=2 if quick else 6,
                                                                         field_degree=d)) for d in fds],
          "Leaf_1, K = 6, constant metric, the default's core fit (ICA, then the proximal alternation for the "
          "cubic terms)")
    Ns = (100, 300) if quick else (100, 1000, 10_000, 100_000)
    sweep("samples", "demonstration samples (total)",
          [(N, f"N={N}", synth(2, samples_per_demo=max(N // 7, 10)),
            dict(SWEEP_BASE, n_components=2 if quick else 6, max_samples=None)) for N in Ns],
          "synthetic 2-D system, 7 demos, all samples used (max_samples=None), K = 6; the SDPs see "
          "the compressed least-squares data only, so only EM (and the compression) may grow")
    return sweeps


def plot_sweeps(sweeps, out_dir):
    paths = {}
    labels = {"total": "total", "em": "EM", "build": "build", "solve": "solver", "steps": "steps",
              "certify": "certify", "verify": "verify", "data": "data"}
    for name, sw in sweeps.items():
        rows = sw["rows"]
        series = {}
        for key, lab in labels.items():
            series[lab] = {"x": [r["x"] for r in rows], "y": [max(r[key], 1e-6) for r in rows]}
        fig = scaling_plot(series, xlabel=sw["xlabel"], ylabel="time (s)",
                           title=f"CDSP fit time vs {sw['xlabel']}")
        p = save_figure(fig, out_dir / f"scaling_{name}")
        paths[name] = {k: str(v) for k, v in p.items()}
        sw["plot"] = p["png"].name
        sw["slopes"] = {lab: _slope([r["x"] for r in rows], [r[key] for r in rows]) for key, lab in labels.items()}
    return paths


def _slope(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0)
    if ok.sum() < 2:
        return None
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


# ---------------------------------------------------------------------- direct vs cvxpy (dynamics step)
def _dynamics_step(shape, K, field_degree, metric_degree, quick):
    """A DynamicsStep on a fitted model's data, as the learner builds it, and the model's metric."""
    demos = load_lasa(shape)
    kw = dict(max_iter=2, verify_samples=500) if quick else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = CDSP(n_components=K, field_degree=field_degree, metric_degree=metric_degree,
                     random_state=0, **PLAIN, **kw).fit(demos)
    return (lambda: scaling_n.dynamics_step_for(model, demos)), model.W_


def run_backends(quick):
    configs = [("Leaf_1", 2 if quick else 6, 1, 0)]
    if not quick:
        configs.append(("Leaf_1", 6, 3, 2))
    out = []
    for shape, K, fd, md in configs:
        make, W = _dynamics_step(shape, K, fd, md, quick)
        rng = np.random.default_rng(0)
        reps = 3 if quick else 15
        Ws = []
        for _ in range(reps):          # metrics near the learned one (same structure, new numbers); scaled
            Ws.append(W * (1.0 + 0.01 * abs(rng.standard_normal())))    # up, so the step stays feasible
        entry = {"shape": shape, "K": K, "field_degree": fd, "metric_degree": md, "reps": reps}
        for backend in ("direct", "cvxpy"):
            dyn = make()
            dyn.prog.solve = functools.partial(type(dyn.prog).solve, dyn.prog, backend=backend)
            dyn.affine_psd &= backend == "direct"           # a lowering of the direct back end only
            t0 = now()
            dyn.solve(W)                                     # first solve: builds the constraints
            first = now() - t0
            wall, solver, core, upd = [], [], [], []
            for Wi in Ws:
                t0 = now()
                _, sol = dyn.solve(Wi)
                wall.append(now() - t0)
                solver.append(timing(sol.timings, "solve", "Solution.timings"))
                upd.append(timing(sol.timings, "build", "Solution.timings"))
                core.append(upd[-1] + timing(sol.timings, "canonicalize", "Solution.timings"))
            entry[backend] = {"first_solve_wall": first, "step_wall": median(wall), "solver": median(solver),
                              "overhead_full": median([w - s for w, s in zip(wall, solver)]),
                              "overhead_update_solve": median(core), "update": median(upd),
                              "sizes": dyn.prog.compile().sizes(), "status": sol.status}
        d, c = entry["direct"], entry["cvxpy"]
        entry["ratios"] = {"cvxpy_over_direct_step": c["step_wall"] / d["step_wall"],
                           "cvxpy_over_direct_overhead": c["overhead_update_solve"] / d["overhead_update_solve"],
                           "cvxpy_over_direct_solver": c["solver"] / d["solver"] if d["solver"] else None}
        out.append(entry)
        log(f"dynamics step {shape} K={K} field {fd} metric {md}: direct step {fmt_s(d['step_wall'])} "
            f"(solver {fmt_s(d['solver'])}, update+solve overhead {fmt_s(d['overhead_update_solve'])}), cvxpy step "
            f"{fmt_s(c['step_wall'])} -> ratio {entry['ratios']['cvxpy_over_direct_step']:.2f}")
    return out


# ---------------------------------------------------------------------- targets and profiles
def evaluate_targets(fits, backends):
    t = {}
    lin = [f for f in fits if f["variant"] == "linear+ICA"]
    t["linear_fit"] = {"max_total": max((f["total"] for f in lin), default=None),
                       "per_shape": {f["shape"]: f["total"] for f in lin}}
    t["linear_fit"]["met"] = t["linear_fit"]["max_total"] <= TARGETS["linear_fit_s"] if lin else None
    for key, vname in (("paper_fit", "paper (metric deg 2, alternating)"), ("cubic_fit", "cubic + metric deg 2")):
        sel = [f for f in fits if f["variant"] == vname]
        t[key] = {"variant": vname, "max_total": max((f["total"] for f in sel), default=None),
                  "per_shape": {f["shape"]: f["total"] for f in sel}, "limit_s": TARGETS[f"{key}_s"]}
        t[key]["met"] = t[key]["max_total"] <= TARGETS[f"{key}_s"] if sel else None
    ov = [b["direct"]["overhead_update_solve"] for b in backends]
    t["resolve"] = {"max_overhead_update_solve": max(ov, default=None),
                    "max_overhead_full_step": max((b["direct"]["overhead_full"] for b in backends), default=None)}
    t["resolve"]["met"] = t["resolve"]["max_overhead_update_solve"] <= TARGETS["resolve_overhead_s"] if ov else None
    return t


def scaling_jobs(scaling) -> list:
    """Profile jobs (title, demos, params) for the n-scaling goals the default's core fit misses
    (:mod:`.scaling_n`): the fit at the largest n (ratio goal), the fit at the n of the worst
    build/solve (build <= solve goal), the cubic preset at n = 3."""
    if not scaling or scaling.get("preset"):
        return []
    g, totals = scaling["goals"], {r["n"]: r["total"] for r in scaling["rows"]}
    core = dict(CORE, n_components=scaling_n.K, random_state=0)
    wanted = {}
    if g["ratio"]["met"] is False:
        wanted[g["ratio"]["n_max"]] = "ratio goal"
    if g["build_over_solve"]["met"] is False:
        wanted.setdefault(g["build_over_solve"]["at_n"], "build <= solve goal")
    jobs = [(f"default core fit, synthetic n = {n} ({why}; {fmt_s(totals[n])} in the scaling run)", synth(n), core)
            for n, why in wanted.items()]
    if g.get("full_n7", {}).get("met") is False:
        jobs.append((f"full default CDSP(), synthetic n = 7 (full-default goal; {fmt_s(g['full_n7']['value'])} in the "
                     "scaling run)", synth(7), dict(n_components=scaling_n.K, random_state=0)))
    if g["cubic_n3"]["met"] is False:
        jobs.append((f"cubic preset, synthetic n = 3 (cubic goal; {fmt_s(g['cubic_n3']['value'])})", synth(3),
                     dict(PRESETS["cubic"], n_components=scaling_n.K, random_state=0)))
    return jobs


def overhead_jobs(overhead) -> list:
    """The profile job (title, demos, params) of the default overhead target if it is missed
    (:mod:`.default_overhead`): the default fit of the paper shape of largest default / core ratio."""
    if not overhead or overhead.get("met") is not False:
        return []
    worst = max(overhead["shapes"], key=lambda r: r["ratio"])
    return [(f"default CDSP() on {worst['shape']} (overhead target; {fmt_s(worst['default_s'])} CPU, "
             f"{worst['ratio']:.1f}x its core fit)", load_lasa(worst["shape"]), {})]


def run_profiles(fits, targets, backends, quick, scaling=None, overhead=None):
    """Profile the slowest fit of each variant that misses its target, the n-scaling fits that miss
    theirs (:func:`scaling_jobs`), the default fit of the paper shape of largest default / core
    ratio if the overhead target is missed (:mod:`.default_overhead`) and the re-solve path."""
    jobs = [] if quick else overhead_jobs(overhead)
    for key, vname in (("linear_fit", "linear+ICA"), ("paper_fit", "paper (metric deg 2, alternating)"),
                       ("cubic_fit", "cubic + metric deg 2")):
        if key in targets and targets[key]["met"] is False and not quick:
            sel = [f for f in fits if f["variant"] == vname]
            worst = max(sel, key=lambda f: f["total"])
            jobs.append((f"{vname} fit on {worst['shape']} (K={worst['K']}, {fmt_s(worst['total'])})",
                         load_lasa(worst["shape"]), dict(worst["params"])))
    jobs += [] if quick else scaling_jobs(scaling)
    profiles = []
    for title, demos, params in jobs:

        def fit(params=params, demos=demos):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return CDSP(**dict(params, allow_uncertified=True)).fit(demos)
        _, prof = profile_call(fit)
        prof["title"] = title
        profiles.append(prof)
        log(f"profiled {title}: top self {prof['self'][0]['function']} {100 * prof['self'][0]['share']:.0f} %")
    if backends and (targets["resolve"]["met"] is False or quick):
        b = backends[-1]
        make, W = _dynamics_step(b["shape"], b["K"], b["field_degree"], b["metric_degree"], quick)
        dyn = make()
        dyn.solve(W)

        def loop():
            for _ in range(3 if quick else 10):
                dyn.solve(W * 1.001)
        _, prof = profile_call(loop)
        prof["title"] = (f"dynamics-step re-solve ×{3 if quick else 10} (direct; {b['shape']} K={b['K']}, "
                         f"field degree {b['field_degree']}, metric degree {b['metric_degree']})")
        profiles.append(prof)
    return profiles


def last_runs(out_dir: Path) -> dict:
    """The one-state evaluator's and DTW's results (``predict``, ``dtw``) from their files, when written."""
    return {name: json.loads((out_dir / f"{name}.json").read_text()) for name in ("predict", "dtw")
            if (out_dir / f"{name}.json").exists()}


def rebuild_summary(out_dir: Path) -> None:
    """summary.md again from the JSON files of the last runs (e.g. after ``scaling_n`` alone)."""
    read = lambda name: json.loads((out_dir / name).read_text())  # noqa: E731
    bench = read("bench.json")
    res = dict(bench, fits=read("fits.json")["fits"], sweeps=read("scaling.json")["sweeps"],
               scaling_n=read("scaling_n.json"), backends=read("backends.json")["dynamics_step"],
               profiles=read("profiles.json")["profiles"])
    if (out_dir / "sos.json").exists():
        res["sos_summary"] = read("sos.json").get("summary")
    if (out_dir / "overhead.json").exists():
        res["overhead"] = read("overhead.json")
    res.update(last_runs(out_dir))
    (out_dir / "summary.md").write_text(summary_markdown(res, out_dir))
    log(f"rebuilt {out_dir}/summary.md from the JSON files")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m problems bench")
    ap.add_argument("--quick", action="store_true", help="tiny sizes (smoke test)")
    ap.add_argument("--out", default=str(BENCH))
    ap.add_argument("--skip", default="", help="comma list of parts to skip: shapes,sweeps,scaling_n,backends,profiles,predict,dtw,overhead")
    ap.add_argument("--summary", action="store_true", help="only rebuild summary.md from the JSON files of the last runs")
    args = ap.parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    if args.summary:
        rebuild_summary(out_dir)
        return 0
    skip = set(filter(None, args.skip.split(",")))
    t_start = now()
    res = {"benchmark": "bench", "quick": args.quick, "environment": environment(), "targets_def": TARGETS}
    res["fits"] = [] if "shapes" in skip else run_shapes(args.quick)

    def keep(part, name, data):             # a skipped part keeps the file of its last run
        if part not in skip:
            write_json(out_dir / name, data)
    keep("shapes", "fits.json", {"environment": res["environment"], "fits": res["fits"]})
    res["overhead"] = None if "overhead" in skip else default_overhead.run(args.quick, log)
    keep("overhead", "overhead.json", {"environment": res["environment"], **(res["overhead"] or {})})
    res["sweeps"] = {} if "sweeps" in skip else run_sweeps(args.quick)
    res["scaling_n"] = None if "scaling_n" in skip else scaling_n.run((2, 3) if args.quick else (2, 3, 4, 5, 6, 7),
                                                                       args.quick, log)
    if res["scaling_n"]:
        res["scaling_n"]["plot"] = scaling_n.plot(res["scaling_n"], out_dir)
        write_json(out_dir / "scaling_n.json", {"environment": res["environment"], **res["scaling_n"]})
    if "sweeps" not in skip:
        plot_sweeps(res["sweeps"], out_dir)
    keep("sweeps", "scaling.json", {"environment": res["environment"], "sweeps": res["sweeps"]})
    res["backends"] = [] if "backends" in skip else run_backends(args.quick)
    keep("backends", "backends.json", {"environment": res["environment"], "dynamics_step": res["backends"]})
    res["targets"] = evaluate_targets(res["fits"], res["backends"])
    res["profiles"] = [] if "profiles" in skip else run_profiles(res["fits"], res["targets"], res["backends"],
                                                                  args.quick, res["scaling_n"], res["overhead"])
    keep("profiles", "profiles.json", {"profiles": res["profiles"]})
    if "predict" not in skip:          # the one-state evaluator against model.predict (predict.json)
        predict.main(["--out", str(out_dir)] + (["--quick"] if args.quick else ["--cubic"]))
    if "dtw" not in skip:              # the DTW distance of the evaluation (dtw.json)
        dtw.main(["--out", str(out_dir)] + (["--quick"] if args.quick else []))
    res.update(last_runs(out_dir))
    sos_json = out_dir / "sos.json"
    if sos_json.exists():
        res["sos_summary"] = json.loads(sos_json.read_text()).get("summary")
    res["elapsed_s"] = now() - t_start
    if skip:        # a partial run leaves the whole-run summary of the last full run in place
        log(f"skipped {sorted(skip)}: bench.json and summary.md not rewritten ({now() - t_start:.0f} s)")
        return 0
    write_json(out_dir / "bench.json", {k: res[k] for k in ("benchmark", "quick", "environment", "targets_def",
                                                            "targets", "elapsed_s")})
    (out_dir / "summary.md").write_text(summary_markdown(res, out_dir))
    log(f"wrote {out_dir}/summary.md and JSON files in {res['elapsed_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

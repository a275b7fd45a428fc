"""problems.sweep: a tiny hyper-parameter sweep on a 2-worker Dask LocalCluster gives the same
numbers, in the same order, as the in-process run."""
from __future__ import annotations

import pytest

from problems.sweep import grid_points, load_data, markdown, sweep
from sosdyn.errors import InputError

GRID = {"n_components": [2], "gamma": [0.05, 0.2], "max_iter": [2], "verify_samples": [300], "random_state": [0]}


def test_grid_points_and_data_names():
    pts = grid_points({"a": [1, 2], "b": ["x"]})
    assert pts == [{"a": 1, "b": "x"}, {"a": 2, "b": "x"}]
    assert load_data("synthetic:2").dim == 2
    with pytest.raises(InputError, match="Try: lasa:NAME"):
        load_data("csv:foo")


def test_tiny_sweep_on_a_local_dask_cluster_matches_the_local_run():
    distributed = pytest.importorskip("distributed")
    local = sweep(["synthetic:2"], GRID, n_jobs=1, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        remote = sweep(["synthetic:2"], GRID, scheduler=cluster.scheduler_address, progress=False)
        ran = sum(w.state.executed_count for w in cluster.workers.values())
    assert ran == 2                                               # both points ran on the cluster's workers
    assert [r["params"]["gamma"] for r in remote] == [0.05, 0.2]  # input order
    for a, b in zip(local, remote):
        assert a["status"] == b["status"] == "ok" and a["certified"] and b["certified"]
        assert b["velocity_rel_error"] == pytest.approx(a["velocity_rel_error"], rel=1e-9)
        assert 0 < b["velocity_rel_error"] < 1
    assert "synthetic:2" in markdown(remote)

"""problems.real_data: the held-out protocol on the shipped real sets (quick run, schema, page, cache)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from problems import real_data
from sosdyn.evaluation import dsopt, realdata


@pytest.mark.slow      # experiment-sized: make test-slow
def test_quick_run_writes_results_page_and_figure(tmp_path):
    paths = real_data.run(("hammer",), ("CDSP default", "GMR", "DMP"), quick=True, out_dir=tmp_path)
    res = json.loads(paths["results"].read_text())
    hammer = res["sets"]["hammer"]
    assert hammer["n_demos"] == 10 and hammer["dim"] == 3 and hammer["units"] == "m (inferred)"
    cdsp, gmr, dmp = (hammer["methods"][m] for m in ("CDSP default", "GMR", "DMP"))
    assert cdsp["n_train"] == 6 and cdsp["n_test"] == 4            # ceil(4 * 10 / 7) = 6
    assert cdsp["certified"] is True and gmr["certified"] is None and dmp["certified"] is None
    for r in (cdsp, gmr, dmp):
        assert not r["error"] and not r["failure"] and len(r["tests"]) == 4
        assert math.isclose(r["ratio"], r["dtwd_mean"] / r["copy_mean"])
        assert r["excursion"] == max(t["excursion"] for t in r["tests"]) >= 0
        assert all(0 <= t["excursion_beyond_start"] <= t["excursion"] for t in r["tests"])
        assert all(t["dtwd"] > 0 and t["copy"] > 0 for t in r["tests"])
        assert r["arrived"] == [sum(t["arrival_ratio"] <= 2 for t in r["tests"]), 4]
    assert cdsp["copy_mean"] == gmr["copy_mean"] == dmp["copy_mean"]   # the reference does not depend on the method
    assert cdsp["targets"]["dmp"] == (cdsp["ratio"] <= dmp["ratio"])
    # the certified bound holds for every measured rollout; GMR has no certificate, so no bound
    assert all(t["excursion"] <= t["excursion_bound"] for t in cdsp["tests"]) and gmr["excursion_bound"] is None
    assert cdsp["excursion_bound"] == max(t["excursion_bound"] for t in cdsp["tests"])
    blocks = res["blocks"]
    assert set(blocks["numbers"]) == {"hammer"} and (tmp_path / blocks["figures"]["dtwd"]).is_file()
    # copy is the per-test-demo minimum over training demos, so copying one chosen by its start scores >= copy
    assert blocks["numbers"]["hammer"]["start_copy_ratio"] >= 1.0
    assert ("starts hammer" in blocks["figures"]) == (cdsp["excursion_beyond_start"] > 0.25)
    assert blocks["numbers"]["hammer"]["dmp_ratio"] == dmp["ratio"]
    assert (tmp_path / blocks["figures"]["metric"]).is_file() and all(r >= 1 for r in blocks["numbers"]["hammer"]["rise"])
    assert cdsp["smoothing_window"] == 13                           # hammer is noisy: Savitzky-Golay on
    page = paths["html"].read_text()
    assert "figures/hammer.png" in page and (tmp_path / "figures" / "hammer.png").read_bytes()[:4] == b"\x89PNG"
    again = real_data.run_job("hammer", "GMR", True, tmp_path / "cache", False)
    assert again["from_cache"] and again["ratio"] == gmr["ratio"]


def test_targets_flag_each_miss():
    entry = {"ratio": 2.5, "excursion_beyond_start": 0.1, "arrival_ratio": 3.0, "certified": True, "error": None,
             "failure": None}
    assert real_data.targets(entry) == {"dtwd": False, "excursion": True, "arrival": False, "certified": True,
                                        "all": False}
    met = dict(entry, ratio=1.4, arrival_ratio=1.0)
    assert real_data.targets(met)["all"] is True
    assert real_data.targets(met, dict(met, ratio=1.2)) == {"dtwd": True, "excursion": True, "arrival": True,
                                                            "certified": True, "dmp": False, "all": False}
    assert real_data.targets(dict(met, excursion_beyond_start=0.3))["excursion"] is False
    assert real_data.targets(dict(entry, ratio=1.4, arrival_ratio=1.0, certified=None))["all"] is False


def test_configs_scores_training_and_test_reproductions(tmp_path):
    from problems import real_data_configs
    path = real_data_configs.run(("hammer",), ("plain",), out_dir=tmp_path)
    row = json.loads(path.read_text())["results"]["hammer|plain"]
    assert row["certified"] and row["train"]["dtwd"] > 0 and math.isfinite(row["train"]["arrival_ratio"])
    _, recorded, test, _ = realdata.prepare(real_data.load("hammer"))
    assert row["test"]["copy"] == pytest.approx(dsopt.nearest_demo_score(recorded, test))
    assert row["train"]["copy"] == 0.0            # from a training start, the nearest training demo is itself


def test_metric_profiles_measure_the_rise_of_the_distance_to_the_goal():
    """M = I, no warp, goal 0, scale 1: D = |x|. A demo straight to the goal never rises (1); one from
    (1, 0) in to (0.5, 0), out to (2, 0) and back rises 2 / 0.5 = 4 times."""
    from types import SimpleNamespace

    from problems.real_data_blocks import metric_profiles
    from sosdyn.lfd.data.demonstrations import Demonstration
    model = SimpleNamespace(W_=np.eye(2)[:, :, None], metric_exps_=np.zeros((1, 2), dtype=int), goal_=np.zeros(2),
                            scale_=1.0, warp_=None, dim_=2)
    t = np.linspace(0, 1, 301)
    straight = Demonstration.from_positions(t, np.column_stack([1 - t, np.zeros_like(t)]))
    x = np.interp(t, [0, 0.3, 0.6, 1], [1, 0.5, 2, 0])
    swing = Demonstration.from_positions(t, np.column_stack([x, np.zeros_like(t)]))
    flat, out_in = metric_profiles(model, [straight, swing])
    assert flat["rise"] == 1.0 and out_in["rise"] == pytest.approx(4.0)
    assert len(out_in["t"]) == len(out_in["d"]) <= 200 and out_in["d"][0] == pytest.approx(1.0)

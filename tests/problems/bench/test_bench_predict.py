"""Smoke test of the single-state predict benchmark (problems.bench.predict)."""
import json

import pytest

from problems.bench import predict
from problems.bench.learner_report import evaluator_rows


@pytest.mark.slow      # experiment-sized: make test-slow
def test_quick_run_writes_timings_and_equality(tmp_path, times_ok, capsys):
    assert predict.main(["--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "predict.json").read_text())
    row = data["rows"][0]
    assert (row["K"], row["n"], row["field_degree"]) == (8, 2, 1)
    times_ok(row, ["predict_s", "predictor_s", "python_export_s"])
    assert row["max_rel_diff"] < 1e-12 and row["speedup_met"] == (row["speedup"] >= data["speedup_target"])
    assert len(evaluator_rows(data, None)) == 2
    assert "predictor" in capsys.readouterr().out

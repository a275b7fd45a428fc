"""Smoke test of the DTW benchmark (problems.bench.dtw) and its rows in the bench summary; no timing
thresholds (the targets are the benchmark's verdicts)."""
import json

from problems.bench import dtw
from problems.bench.learner_report import evaluator_rows


def test_quick_run_writes_both_sizes_and_the_summary_row(tmp_path, times_ok):
    assert dtw.main(["--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "dtw.json").read_text())
    assert [tuple(r["points"]) for r in data["rows"]] == list(dtw.TARGETS_S)
    for r in data["rows"]:
        times_ok(r, ["median_s"])
        assert r["met"] == (r["median_s"] <= r["target_s"]) and r["repeats"] == 3
    assert data["met"] == all(r["met"] for r in data["rows"])
    (row,) = evaluator_rows(None, data)
    assert row[0] == "DTW 1000 × 1000 ≤ 500.0 ms, DTW 3000 × 500 ≤ 1.00 s" and row[1] in ("**met**", "**missed**")

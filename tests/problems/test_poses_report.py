"""``python -m problems poses --quick``: the held-out table, the detour tests and the far starts on openbox."""
from __future__ import annotations

import json

import pytest

from problems import poses


@pytest.mark.slow
def test_quick_poses_report(tmp_path):
    assert poses.main(["--quick", "--out", str(tmp_path)]) == 0
    (task,) = json.loads((tmp_path / "results.json").read_text())["tasks"]
    assert task["task"] == "openbox" and task["certified"] and task["n_test"] == 3
    assert task["detours"]["max_displacement_frac"] == 0.0                # the cascade: not a micrometre
    assert len(task["detours"]["cases"]) == 16 and task["far_starts"]["n"] == 36
    assert task["far_starts"]["max_angle_rise_deg"] == 0.0
    t = task["targets"]
    assert t["final_pos_le_1pct"] and t["final_ang_le_1deg"] and t["detour_lt_1pct"] and t["far_starts_converge"]
    assert task["excursion_bound"] is not None
    page = (tmp_path / "index.html").read_text()
    for name in ("openbox_paths.png", "openbox_orientation.png", "openbox_detours.png"):
        assert (tmp_path / name).is_file() and name in page

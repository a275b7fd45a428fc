"""problems.winding: the held-out protocol on the winding set (quick run, rollouts read at the demos'
period, schema, page, figures, cache)."""
from __future__ import annotations

import json
import math

from problems import winding


def test_quick_run_writes_results_page_and_figures(tmp_path):
    paths = winding.run(("winding/hook",), ("CDSP before", "CDSP default"), quick=True, out_dir=tmp_path)
    res = json.loads(paths["results"].read_text())
    hook = res["sets"]["winding/hook"]
    for m in ("CDSP before", "CDSP default"):
        r = hook["methods"][m]
        assert not r["error"] and r["certified"] is True and len(r["tests"]) == 3      # 4 train, 3 test
        assert math.isclose(r["ratio"], r["dtwd_mean"] / hook["copy"])
        assert r["excursion"] == max(t["excursion"] for t in r["tests"])
        assert r["met"] == (r["ratio"] <= 3 and r["excursion"] <= 0.25 and r["arrival_ratio"] <= 2)
    assert hook["methods"]["CDSP before"]["kept"] in ("none", *winding.BEFORE_WARPS)
    page = paths["html"].read_text()
    assert "figures/winding__hook.png" in page and "figures/overview.png" in page
    assert (tmp_path / "figures" / "winding__hook.png").read_bytes()[:4] == b"\x89PNG"
    again = winding.run_job("winding/hook", "CDSP default", True, tmp_path / "cache", False)
    assert again["from_cache"] and again["ratio"] == hook["methods"]["CDSP default"]["ratio"]

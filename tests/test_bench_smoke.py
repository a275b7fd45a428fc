"""Smoke run of both benchmarks' code paths at reduced size (no timing assertions)."""
import json
import math

import pytest

pytest.importorskip("SumOfSquares")
pytest.importorskip("pyinstrument")


def _times_ok(d, keys):
    for k in keys:
        v = d[k]
        assert v is not None and math.isfinite(v) and v > 0, (k, v)


def test_bench_sos_quick(tmp_path):
    from problems import bench_sos
    assert bench_sos.main(["--quick", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "sos.json").read_text())
    assert {"problems", "summary", "targets", "environment", "profiles"} <= set(res)
    names = [p["name"] for p in res["problems"]]
    assert any(n.startswith("dense degree-6") for n in names)
    assert any(n.startswith("CDSP metric step") for n in names)
    for p in res["problems"]:
        for backend in ("direct", "cvxpy"):
            _times_ok(p[backend], ("build", "canonicalize", "solve"))
            assert p[backend]["sizes"]["variables"] > 0
        theirs = p["sumofsquares"]
        assert theirs is not None and "error" not in theirs, theirs
        _times_ok(theirs, ("build", "solve"))
        assert p["ratios"]["build_theirs_over_ours"] > 0
        assert p["status_ok"], (p["name"], p["direct"]["status"])
    resolved = [p["resolve"]["direct"] for p in res["problems"] if p["resolve"]["direct"]]
    assert resolved and all(r["overhead"] > 0 and r["update"] > 0 for r in resolved)
    for key in ("build_share", "resolve", "build_speedup"):
        assert "met" in res["summary"][key]
    md = (tmp_path / "sos.md").read_text()
    assert "## Targets" in md and "SumOfSquares" in md


def test_bench_learner_quick(tmp_path):
    from problems import bench
    assert bench.main(["--quick", "--out", str(tmp_path)]) == 0
    for name in ("fits.json", "scaling.json", "backends.json", "profiles.json", "bench.json", "summary.md"):
        assert (tmp_path / name).exists(), name
    fits = json.loads((tmp_path / "fits.json").read_text())["fits"]
    assert fits
    for f in fits:
        _times_ok(f, ("total", "em", "build", "canonicalize", "solve", "verify"))
        assert f["sdp_solves"] > 0
    sweeps = json.loads((tmp_path / "scaling.json").read_text())["sweeps"]
    assert set(sweeps) == {"K", "n", "metric", "field", "samples"}
    for sw in sweeps.values():
        assert (tmp_path / sw["plot"]).exists()
        for r in sw["rows"]:
            _times_ok(r, ("total", "em", "solve"))
    back = json.loads((tmp_path / "backends.json").read_text())["dynamics_step"]
    for b in back:
        for backend in ("direct", "cvxpy"):
            _times_ok(b[backend], ("step_wall", "solver", "overhead_update_solve"))
        assert b["ratios"]["cvxpy_over_direct_step"] > 0
    targets = json.loads((tmp_path / "bench.json").read_text())["targets"]
    assert {"linear_fit", "resolve"} <= set(targets)
    profiles = json.loads((tmp_path / "profiles.json").read_text())["profiles"]
    assert profiles and profiles[0]["self"]
    assert "## Targets" in (tmp_path / "summary.md").read_text()

"""problems.bench.sos: a smoke run at reduced size (no timing assertions)."""
import json

import pytest

pytest.importorskip("SumOfSquares")
pytest.importorskip("pyinstrument")

from problems.bench import sos as bench_sos  # noqa: E402


def test_bench_sos_quick(tmp_path, times_ok):
    assert bench_sos.main(["--quick", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "sos.json").read_text())
    assert {"problems", "summary", "targets", "environment", "profiles"} <= set(res)
    names = [p["name"] for p in res["problems"]]
    assert any(n.startswith("dense degree-6") for n in names)
    assert any(n.startswith("CDSP metric step") for n in names)
    for p in res["problems"]:
        for backend in ("direct", "cvxpy"):
            times_ok(p[backend], ("build", "canonicalize", "solve"))
            assert p[backend]["sizes"]["variables"] > 0
        theirs = p["sumofsquares"]
        assert theirs is not None and "error" not in theirs, theirs
        times_ok(theirs, ("build", "solve"))
        assert p["ratios"]["build_theirs_over_ours"] > 0
        assert p["status_ok"], (p["name"], p["direct"]["status"])
    resolved = [p["resolve"]["direct"] for p in res["problems"] if p["resolve"]["direct"]]
    assert resolved and all(r["overhead"] > 0 and r["update"] > 0 for r in resolved)
    for key in ("build_share", "resolve", "build_speedup"):
        assert "met" in res["summary"][key]
    md = (tmp_path / "sos.md").read_text()
    assert "## Targets" in md and "SumOfSquares" in md

"""problems.bench.sos: a smoke run at reduced size (no timing assertions)."""
import json

import pytest

pytest.importorskip("SumOfSquares")
pytest.importorskip("pyinstrument")

from problems.bench import drake_problems, sparse_problems
from problems.bench import sos as bench_sos


@pytest.mark.slow      # experiment-sized: make test-slow
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
    drake = drake_problems.available() is not None
    for p in res["problems"]:
        d = p["drake"]
        if not drake:
            assert d is None
        elif p["name"] in drake_problems.NOT_WRITTEN:
            assert "skipped" in d
        else:
            times_ok(d, ("build", "canonicalize", "solve"))
            assert d["ratios"]["total"] > 0 and d["status"] == p["direct"]["status"].replace("_inaccurate", "")
    assert res["summary"]["drake"]["met"] in ((True, False) if drake else (None,))
    assert [(r["problem"], r["n"], r["variant"]) for r in res["sparse"]] == [
        (f, 4, v) for f in sparse_problems.ROW_PROBLEMS for v in sparse_problems.VARIANTS]
    # every returned bound is a bound, and right: the known minima 1 (Wood) and 0 (Rosenbrock, whose Gram
    # blocks are singular: bounded on the face of the solver's kernel, docs/sos-semantics.md)
    dense = {r["problem"]: r for r in res["sparse"] if r["variant"] == "dense"}
    assert dense["chained Wood"]["bound_ok"] and dense["chained Wood"]["bound"] == pytest.approx(1.0, abs=1e-4)
    assert dense["chained Rosenbrock"]["bound_ok"] and -1e-4 <= dense["chained Rosenbrock"]["bound"] <= 0.0
    scaling = {(r["problem"], r["n"]): r for r in res["sparse_scaling"]}
    assert scaling[("chained Wood", 100)]["bound"] == pytest.approx(1.0, abs=1e-4)     # known minimum 1
    assert scaling[("Broyden tridiagonal", 100)]["bound"] == pytest.approx(0.0, abs=1e-4)
    split = res["build_split"]
    assert split["problem"] in {"Motzkin M", "quartic form"}           # the one-polynomial problems here
    assert split["stages"]["sosdyn"]["total"]["min"] > 0
    md = (tmp_path / "sos.md").read_text()
    assert "## Targets" in md and "SumOfSquares" in md and "## Sparsity" in md and "## Sparse scaling" in md
    assert ("## Side by side with Drake" in md) and ("at least as fast as Drake" in md)

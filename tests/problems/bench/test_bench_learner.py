"""problems.bench.learner: a smoke run at reduced size; the fit time is split by public timing
data only (no timing thresholds)."""
import json

import pytest

pytest.importorskip("SumOfSquares")
pytest.importorskip("pyinstrument")

from problems.bench import learner  # noqa: E402
from problems.bench.profiling import ROOT, _short_path  # noqa: E402
from problems.bench.timing import timing  # noqa: E402
from sosdyn.lfd.fit.warp import AUTO_WARPS  # noqa: E402


@pytest.mark.slow      # experiment-sized: make test-slow
def test_bench_learner_quick(tmp_path, times_ok):
    assert learner.main(["--quick", "--out", str(tmp_path)]) == 0
    for name in ("fits.json", "scaling.json", "backends.json", "profiles.json", "bench.json", "summary.md"):
        assert (tmp_path / name).exists(), name
    fits = json.loads((tmp_path / "fits.json").read_text())["fits"]
    assert fits
    for f in fits:
        times_ok(f, ("total", "em", "build", "solve", "certify", "verify"))
        assert f["sdp_solves"] > 1
        assert f["build"] + f["solve"] + f["steps"] == pytest.approx(f["learn"])
    sweeps = json.loads((tmp_path / "scaling.json").read_text())["sweeps"]
    assert set(sweeps) == {"K", "metric", "field", "samples"}
    for sw in sweeps.values():
        assert (tmp_path / sw["plot"]).exists()
        for r in sw["rows"]:
            times_ok(r, ("total", "em", "solve"))
    back = json.loads((tmp_path / "backends.json").read_text())["dynamics_step"]
    for b in back:
        for backend in ("direct", "cvxpy"):
            times_ok(b[backend], ("step_wall", "solver", "overhead_update_solve"))
        assert b["ratios"]["cvxpy_over_direct_step"] > 0
    scal = json.loads((tmp_path / "scaling_n.json").read_text())
    assert [r["n"] for r in scal["rows"]] == [2, 3] and (tmp_path / scal["plot"]).exists()
    for r in scal["rows"]:
        times_ok(r, ("total", "em", "build", "solve", "verify", "resolve_overhead", "solve_check"))
        assert r["build"] >= r["sos_build"] > 0 and r["build_over_solve"] == pytest.approx(r["build"] / r["solve"])
        steps = r["per_step"]                   # the solver split by step kind adds up to the whole
        assert set(steps) == {"dynamics", "ica"} and sum(s["sdps"] for s in steps.values()) == r["sdp_solves"]
        assert sum(s["solve"] for s in steps.values()) == pytest.approx(r["solve"])
        assert sum(s["iterations"] for s in steps.values()) == r["iterations"]
    times_ok(scal["joint7"]["core"], ("total", "em", "build", "solve", "verify"))
    assert scal["joint7"]["core"]["certified"] and scal["joint7"]["full"] > 0
    assert scal["goals"]["joint7_core"]["value"] == scal["joint7"]["core"]["total"]
    assert scal["goals"]["ratio"]["value"] == pytest.approx(scal["rows"][1]["total"] / scal["rows"][0]["total"])
    assert "### state dimension n" in (tmp_path / "summary.md").read_text()
    targets = json.loads((tmp_path / "bench.json").read_text())["targets"]
    assert {"linear_fit", "resolve"} <= set(targets)
    profiles = json.loads((tmp_path / "profiles.json").read_text())["profiles"]
    assert profiles and profiles[0]["self"]
    assert "## Targets" in (tmp_path / "summary.md").read_text()
    over = json.loads((tmp_path / "overhead.json").read_text())
    assert [r["shape"] for r in over["shapes"]] == ["BendedLine"]
    assert over["ratio"] == pytest.approx(over["default_s"] / over["core_s"]) and over["default_s"] > 0
    assert set(over["shapes"][0]["warp_scores"]) == {"none", *AUTO_WARPS}
    assert "default CDSP() ≤ 2x its plain core" in (tmp_path / "summary.md").read_text()


def test_a_missing_timing_is_an_error_not_zero():
    assert timing({"solve": 0.25}, "solve", "Solution.timings") == 0.25
    with pytest.raises(KeyError, match="Solution.timings records no 'canonicalize' timing"):
        timing({"solve": 0.25}, "canonicalize", "Solution.timings")


def test_a_partial_run_leaves_the_skipped_parts_files_alone(tmp_path):
    before = {name: f"{{\"kept\": \"{name}\"}}" for name in
              ("fits.json", "scaling.json", "backends.json", "profiles.json", "bench.json", "summary.md",
               "overhead.json")}
    for name, text in before.items():
        (tmp_path / name).write_text(text)
    parts = "shapes,sweeps,scaling_n,backends,profiles,predict,overhead"
    assert learner.main(["--quick", "--skip", parts, "--out", str(tmp_path)]) == 0
    assert {name: (tmp_path / name).read_text() for name in before} == before


def test_missed_issue_26_targets_get_a_profile_job():
    """The default-overhead target and the full default at n = 7, when missed, each get a profile job
    (the fit that misses it); met or not measured: none."""
    over = {"met": False, "shapes": [{"shape": "Leaf_2", "ratio": 4.0, "default_s": 1.2},
                                     {"shape": "Leaf_1", "ratio": 6.5, "default_s": 1.9}]}
    (title, demos, params), = learner.overhead_jobs(over)
    assert "Leaf_1" in title and demos.name == "Leaf_1" and params == {}
    assert learner.overhead_jobs(dict(over, met=True)) == [] and learner.overhead_jobs(None) == []
    goals = {"ratio": {"met": True}, "build_over_solve": {"met": True}, "cubic_n3": {"met": True},
             "full_n7": {"met": False, "value": 12.5}}
    jobs = learner.scaling_jobs({"goals": goals, "rows": [{"n": 7, "total": 4.0}]})
    assert [j[0].split(" (")[0] for j in jobs] == ["full default CDSP(), synthetic n = 7"]
    assert jobs[0][1].dim == 7 and "warp" not in jobs[0][2]


def test_profiles_name_files_from_this_checkout_whichever_its_folder():
    """A profile's rows name sosdyn's files as sosdyn/... from any checkout (a worktree too), so the
    inclusive table of sosdyn functions is not empty; installed packages from site-packages/."""
    assert _short_path(ROOT + "sosdyn/lfd/fit/warp.py") == "sosdyn/lfd/fit/warp.py"
    assert _short_path("/opt/venv/lib/python3.11/site-packages/numpy/linalg/_linalg.py") == "numpy/linalg/_linalg.py"
    assert _short_path("/elsewhere/a/b.py") == "b.py"

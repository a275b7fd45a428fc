"""problems.report and the figure experiments: figures, findings and the page from the cache."""
from __future__ import annotations

import json


from problems import fig1, fig2, fig3, fig4
from problems.results import assemble
from problems.settings import SEED
from sosdyn.report.html import render_html


def test_figures_and_report_from_cache(toy, toy_shape):
    ctx, entries = toy
    specs = {}
    for mod in (fig1, fig2, fig3, fig4):
        specs.update(mod.figure(entries, ctx))
    assert set(specs) == {"fig1", "fig2", "fig3", "fig4"}
    for spec in specs.values():
        assert (ctx.out_dir / spec["png"]).stat().st_size > 5_000
    results = assemble(entries, ctx.shapes, ctx.methods, ctx.config, specs, command="test")
    titles = [f["title"] for f in results["findings"]]
    assert len(titles) == 4 and titles[0].startswith("The paper")
    assert all(f["numbers"] for f in results["findings"])
    assert results["meta"]["seed"] == SEED and "numpy" in results["meta"]["packages"]
    assert list(results["accuracy"]) == [toy_shape.name]
    json.dumps(results)
    html = render_html(results, ctx.out_dir).read_text()
    assert "Plain alternation" in html and "CDSP-cubic" in html and "not run" not in html.split("Accuracy")[0][-50:]
    assert "<b>" in html and "&lt;b&gt;" not in html      # the findings' markup subset survives


def test_fig1_shows_the_default_cdsp(toy, toy_shape):
    """Fig. 1 (and the per-shape pages) draw the model a user gets from CDSP(): every
    parameter at its default, not a variant (the old report drew CDSP-cubic and CDSP-ICA)."""
    import sosdyn as sd
    from problems.lasa_all import FIELD_METHOD
    from problems.settings import DEFAULT_METHOD, METHODS

    assert fig1.METHODS == (DEFAULT_METHOD,) and FIELD_METHOD == DEFAULT_METHOD
    model = METHODS[DEFAULT_METHOD].factory(toy_shape, quick=False)
    assert model.get_params() == sd.CDSP().get_params()
    ctx, entries = toy
    spec = fig1.figure(entries, ctx)["fig1"]
    assert "default CDSP()" in spec["caption"] and "CDSP-cubic" not in spec["caption"]


def test_captions_state_how_long_the_runs_last(toy):
    """Fig. 1 and Fig. 3 say that runs continue until they are within the goal tolerance
    (the old Fig. 3 cut them at 1.5x the demonstration and only said so)."""
    ctx, entries = toy
    cfg = ctx.config
    for mod in (fig1, fig3):
        (spec,) = mod.figure(entries, ctx).values()
        assert f"within {cfg.goal_tol:g} mm of" in spec["caption"]
        assert f"at most {cfg.max_duration_factor:g}x" in spec["caption"]


def test_drawn_reproductions_reach_the_goal(toy, toy_shape):
    """Every reproduction the default model's Fig. 1 panel draws ends within the goal
    tolerance (rolled out past the demonstration's duration when needed)."""
    import numpy as np

    from problems.settings import DEFAULT_METHOD, load_shape

    ctx, entries = toy
    goal = load_shape(toy_shape, ctx.config).goal
    for rep in entries[toy_shape.name][DEFAULT_METHOD]["plot"]["reproductions"]:
        assert np.linalg.norm(np.asarray(rep)[-1] - goal) <= ctx.config.goal_tol + 0.5  # every 4th sample kept

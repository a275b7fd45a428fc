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

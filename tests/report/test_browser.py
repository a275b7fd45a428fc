"""The report opened in a real browser (Debian's chromium driven by playwright)."""

from __future__ import annotations

from pathlib import Path

import pytest

from sosdyn.report import figures as F
from sosdyn.report import html as H

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not CHROMIUM.exists(),
                       reason="needs Debian's chromium at /usr/bin/chromium (apt-get install chromium)"),
]


@pytest.fixture
def report_page(tmp_path, results_factory, field, demos_factory):
    """index.html with an SVG figure, a PNG-only figure and a missing one, open in chromium."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    results = results_factory()
    demos = demos_factory(2)
    F.save_figure(F.accuracy_bars(results["accuracy"]), tmp_path / "figures" / "fig2")
    F.save_figure(F.streamlines(None, field, demos, demos, [0, 0], grid=20, density=0.5),
                  tmp_path / "figures" / "fig1")
    (tmp_path / "figures" / "fig1.svg").unlink()
    results["figures"] = {
        "fig1": {"svg": "figures/fig1.svg", "png": "figures/fig1.png", "caption": "Streamlines."},
        "fig2": {"svg": "figures/fig2.svg", "png": "figures/fig2.png", "caption": "Accuracy."},
        "fig9": {"svg": "figures/fig9.svg", "caption": "Never drawn."},
    }
    index = H.render_html(results, tmp_path)
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        page = browser.new_page()
        problems: list[str] = []
        page.on("console", lambda msg: problems.append(msg.text) if msg.type == "error" else None)
        page.on("pageerror", lambda exc: problems.append(str(exc)))
        page.on("requestfailed", lambda req: problems.append(f"request failed: {req.url}"))
        page.goto(index.as_uri(), wait_until="load")
        yield page, problems
        browser.close()


def test_figures_decode_tables_are_complete_and_console_is_clean(report_page):
    page, problems = report_page
    images = page.eval_on_selector_all(
        "figure img", "els => els.map(e => ({src: e.src.slice(0, 30), ok: e.complete && e.naturalWidth > 0,"
        " w: e.naturalWidth}))")
    assert len(images) == 2
    assert all(img["ok"] for img in images), images
    assert {img["src"][:19] for img in images} == {"data:image/png;base", "data:image/svg+xml;"}
    # the figure that was never drawn is a visible placeholder, not a broken image
    assert "Figure file missing" in page.inner_text("#fig-fig9")
    # inline <svg> elements, if any, must have a size too
    assert page.eval_on_selector_all("svg", "els => els.every(e => e.getBBox().width > 0)")

    rows = {t: page.locator(f"table#{t} > tbody > tr").count()
            for t in ("accuracy", "robustness", "certificates", "timings", "methods", "packages")}
    assert rows == {"accuracy": 12, "robustness": 12, "certificates": 3, "timings": 12,
                    "methods": 4, "packages": 2}
    assert page.locator(".finding").count() == 2
    assert page.locator("table#accuracy td.best").count() > 0
    assert problems == []
    # self-contained: nothing but data: URIs was loaded
    assert page.evaluate("() => performance.getEntriesByType('resource')"
                         ".map(r => r.name).filter(n => !n.startsWith('data:'))") == []

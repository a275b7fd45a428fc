"""The reports opened in a real browser (Debian's chromium driven by playwright): a rendered
report, and the committed index with every link it holds followed."""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

from problems.report_pages import page_files
from sosdyn.report import figures as F
from sosdyn.report import html as H

REPORTS = Path(__file__).resolve().parents[2] / "reports"

pytestmark = pytest.mark.browser


@pytest.fixture
def report_page(tmp_path, browser, results_factory, field, demos_factory):
    """index.html with an SVG figure, a PNG-only figure and a missing one, open in chromium."""
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
    page = browser.new_page()
    problems: list[str] = []
    page.on("console", lambda msg: problems.append(msg.text) if msg.type == "error" else None)
    page.on("pageerror", lambda exc: problems.append(str(exc)))
    page.on("requestfailed", lambda req: problems.append(f"request failed: {req.url}"))
    page.goto(index.as_uri(), wait_until="load")
    return page, problems


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


def _visit(browser, url: str) -> tuple[list[str], list[str]]:
    """Open ``url`` in a new tab: (what is wrong on it: a failed request, an image that did not
    load, a link to a fragment the page lacks or to no file; the links of its report table)."""
    page = browser.new_page()
    failed: list[str] = []
    page.on("requestfailed", lambda req: failed.append(f"{url}: request failed {req.url}"))
    page.goto(url, wait_until="load")
    broken = page.eval_on_selector_all("img", "els => els.filter(e => !(e.complete && e.naturalWidth > 0))"
                                              ".map(e => e.src.slice(0, 80))")
    failed += [f"{url}: image did not load {src}" for src in broken]
    ids = set(page.eval_on_selector_all("[id]", "els => els.map(e => e.id)"))
    for href in page.eval_on_selector_all("a[href]", "els => els.map(e => e.href)"):
        target = urlparse(href)
        if target.scheme != "file":
            continue                                     # no network in tests
        if target.fragment and unquote(target.path) == unquote(urlparse(url).path):
            if target.fragment not in ids:
                failed.append(f"{url}: no #{target.fragment}")
        elif not Path(unquote(target.path)).exists():
            failed.append(f"{url}: link to a missing file {target.path}")
    reports = page.eval_on_selector_all("#reports a[href]", "els => els.map(e => e.href)")
    page.close()
    return failed, reports


def test_the_index_links_every_report_and_every_link_leads_somewhere(browser):
    """The committed reports/index.html links every page under reports/; each linked page opens,
    its images load, and its own links lead to files that exist."""
    index = REPORTS / "index.html"
    problems, links = _visit(browser, index.as_uri())
    linked = {Path(unquote(urlparse(h).path)).resolve() for h in links}
    pages = {p.resolve() for p in page_files(REPORTS)} - {index.resolve()}
    assert pages <= linked, f"not linked from the index (make report): {sorted(map(str, pages - linked))}"
    for href in links:
        if urlparse(href).path.endswith(".html") and urlparse(href).path != urlparse(index.as_uri()).path:
            problems += _visit(browser, href)[0]
    assert problems == []

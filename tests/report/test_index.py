"""The committed reports say what their data gives: the user report's findings, its methods table
and the index of all reports are what the code writes from the committed data files (so none can
drift from them), every number a sentence quotes is in its data, and every page under reports/
is linked from reports/index.html."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from markupsafe import escape

import sosdyn as sd
from problems.findings import findings, unquoted
from problems.report_pages import PAGES, index_pages, page_files
from problems.results import cdsp_summary, methods_section, redescribed
from problems.settings import METHODS, PAPER_SHAPES
from sosdyn.report.html import load_results, markup

REPORTS = Path(__file__).resolve().parents[2] / "reports"
STALE = "reports/index.html is out of step with the data: run `make report`"


@pytest.fixture(scope="module")
def committed():
    return load_results(REPORTS / "results.json")


def test_every_page_under_reports_is_linked_from_the_index():
    html = (REPORTS / "index.html").read_text()
    hrefs = set(re.findall(r'<a href="([^"#]+)"', html))
    pages = {p.relative_to(REPORTS).as_posix() for p in page_files(REPORTS)} - {"index.html"}
    assert pages and pages <= hrefs, f"{STALE}; not linked: {sorted(pages - hrefs)}"


def test_the_findings_are_what_the_committed_data_gives(committed):
    assert committed["findings"] == findings(committed), STALE
    html = (REPORTS / "index.html").read_text()
    for f in committed["findings"]:
        assert str(markup(f["text"])) in html, STALE
        assert unquoted(f["text"], f["numbers"]) == []


def test_the_index_rows_are_what_each_page_data_gives(committed):
    assert committed["pages"] == index_pages(REPORTS, committed), STALE
    html = (REPORTS / "index.html").read_text()
    for row in committed["pages"]:
        assert row["finding"] and not row["finding"].startswith("(no finding"), row
        assert unquoted(row["finding"], row["numbers"]) == []
        assert str(escape(row["finding"])) in html, STALE


def test_every_registered_page_reads_its_data_and_quotes_only_it():
    for page in PAGES:
        data = REPORTS / page.folder / page.data
        if data.is_file():
            text, numbers = page.finding(json.loads(data.read_text()))
            assert text and unquoted(text, numbers) == [], page.folder


def test_the_committed_methods_table_is_written_from_its_settings(committed):
    """The old table said the default CDSP() used corrective refits; it does not."""
    assert committed["methods"] == redescribed(committed["methods"]), STALE
    default = committed["methods"]["CDSP"]
    assert default["settings"]["corrective_rounds"] == 0
    assert "no corrective refits" in default["description"]


def test_methods_are_described_from_their_parameters():
    section = methods_section(PAPER_SHAPES)
    defaults = sd.CDSP().get_params()
    for name, spec in section.items():
        if METHODS[name].kind != "cdsp":
            continue
        assert spec["description"] == f"{METHODS[name].description} {cdsp_summary(spec['settings'])}"
        # what a method stands for says nothing its parameters decide
        assert not re.search(r"corrective|warp|ICA|alternat|linear|cubic|constant|K =", METHODS[name].description)
    default = section["CDSP"]
    assert {k: default["settings"][k] for k in ("corrective_rounds", "warp", "gating", "n_components")} == \
        {k: defaults[k] for k in ("corrective_rounds", "warp", "gating", "n_components")}
    assert ("no corrective refits" in default["description"]) == (defaults["corrective_rounds"] == 0)
    assert "2 rounds of corrective refits" in cdsp_summary({"corrective_rounds": 2})
    assert "no pre-warp" in cdsp_summary({"warp": "none"}) and "(warp='auto')" in cdsp_summary({"warp": "auto"})
    assert "M = I" in cdsp_summary({"metric": "identity"}) and "tempered gating" in cdsp_summary({"gating": "tempered"})


def test_the_docs_home_lists_every_report_page():
    home = (REPORTS.parent / "docs" / "index.md").read_text()
    for html in page_files(REPORTS):
        folder = html.parent.relative_to(REPORTS).as_posix()
        assert (f"`reports/{folder}/`" if folder != "." else "`reports/index.html`") in home, folder

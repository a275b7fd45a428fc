"""The HTML report: tables, findings, embedded figures, graceful gaps, and the PDF."""

from __future__ import annotations

import json
import subprocess
from html.parser import HTMLParser

import matplotlib.image as mpimg
import pytest

from sosdyn.errors import InputError
from sosdyn.report import figures as F
from sosdyn.report import html as H

SECTIONS = ("findings", "figures", "accuracy", "robustness", "certificates", "timings",
            "methods", "meta")


class Tables(HTMLParser):
    """Counts the body rows of each ``<table id=...>`` and collects ``<img src>``."""

    def __init__(self, text: str):
        super().__init__()
        self.rows: dict[str, int] = {}
        self.images: list[str] = []
        self._table: str | None = None
        self._in_body = False
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table":
            self._table = attrs.get("id")
            self.rows.setdefault(self._table, 0)
        elif tag == "tbody":
            self._in_body = True
        elif tag == "tr" and self._in_body:
            self.rows[self._table] += 1
        elif tag == "img":
            self.images.append(attrs["src"])

    def handle_endtag(self, tag):
        if tag == "tbody":
            self._in_body = False


@pytest.fixture
def figure_files(tmp_path, results):
    """Two real figures under tmp_path/figures, as the results' "figures" section."""
    F.save_figure(F.accuracy_bars(results["accuracy"]), tmp_path / "figures" / "fig2")
    F.save_figure(F.robustness_bars(results["robustness"]), tmp_path / "figures" / "fig3")
    return {name: {"svg": f"figures/{name}.svg", "png": f"figures/{name}.png", "caption": cap}
            for name, cap in (("fig2", "Accuracy per shape."), ("fig3", "Robustness per shape."))}


def test_full_report_has_every_row(tmp_path, results_factory, figure_files):
    results = results_factory(figures=figure_files)
    path = H.render_html(results, tmp_path)
    assert path == tmp_path / "index.html"
    text = path.read_text()
    tables = Tables(text)
    assert tables.rows["accuracy"] == 3 * 4
    assert tables.rows["robustness"] == 3 * 4
    assert tables.rows["certificates"] == 3          # CDSP only carries a certificate
    assert tables.rows["timings"] == 3 * 4
    assert tables.rows["methods"] == 4
    assert tables.rows["packages"] == 2
    assert text.count('class="finding"') == 2
    assert "Not run." not in text
    # findings: text is trusted HTML, numbers formatted
    assert "learned metric <i>M(x)</i> is constant" in text
    assert "max relative non-constant part: <b>2.10e-07</b>" in text
    # figures are embedded, not linked: the page is self-contained
    assert len(tables.images) == 2
    assert all(src.startswith("data:image/svg+xml;base64,") for src in tables.images)
    assert 'src="figures/' not in text
    # the benchmarks are another page: named, not linked while it does not exist
    assert "reports/bench/index.html" in text and 'href="bench/index.html"' not in text
    # every table scrolls sideways in its own box instead of running off the page
    assert text.count('<div class="table-wrap"><table id=') == len(tables.rows)
    assert ".table-wrap { overflow-x: auto;" in text


def test_accuracy_cells_show_mean_std_and_best(tmp_path, results):
    results["accuracy"] = {"Leaf_1": {
        "CDSP": {"sea": {"mean": 512.34, "std": 12.345}, "grid_convergence": 1.0, "certified": True},
        "DMP": {"sea": {"mean": 900.0, "std": 50.0}, "grid_convergence": None, "certified": None},
    }}
    text = H.render_html(results, tmp_path).read_text()
    assert '<td class="best">512 ± 12</td>' in text
    assert "<td>900 ± 50</td>" in text
    assert "<td>✓</td>" in text and "<td>n/a</td>" in text


def test_titles_are_escaped_and_finding_text_keeps_only_the_markup_subset(tmp_path, results):
    results["findings"] = [{"title": "<script>alert(1)</script>",
                            "text": "<b>bold</b> <i>it</i><br>a &gt; b &#8804; c <img src=x onerror=alert(1)>"
                                    "<script>x</script> &lt;b&gt;", "numbers": {}}]
    text = H.render_html(results, tmp_path).read_text()
    assert "<script>" not in text and "<img src=x" not in text
    assert "&lt;script&gt;alert(1)" in text and "&lt;img src=x onerror=alert(1)&gt;" in text
    assert "<b>bold</b> <i>it</i><br>a &gt; b &#8804; c" in text
    assert "&lt;b&gt;" in text                         # an escaped tag stays text


def test_markup_subset():
    assert H.markup("<b>x</b> & <u>y</u> &amp; <br/>") == "<b>x</b> &amp; &lt;u&gt;y&lt;/u&gt; &amp; &lt;br/&gt;"


def test_empty_results_say_not_run(tmp_path):
    text = H.render_html({}, tmp_path).read_text()
    assert text.count("Not run.") == len(SECTIONS)
    assert Tables(text).rows == {}


@pytest.mark.parametrize("section", SECTIONS)
def test_each_section_alone_can_be_missing(tmp_path, results, section):
    results.pop(section, None)
    text = H.render_html(results, tmp_path).read_text()
    assert text.count("Not run.") == 1 + (section != "figures")   # results has no figures


def test_malformed_section_is_reported_and_others_still_render(tmp_path, results):
    results["accuracy"] = ["not", "a", "dict"]
    results["timings"]["Leaf_1"]["CDSP"] = {}                     # partial entry: dashes
    text = H.render_html(results, tmp_path).read_text()
    assert "Could not be rendered: AttributeError" in text
    assert Tables(text).rows["robustness"] == 12
    assert Tables(text).rows["timings"] == 12 and "<td>—</td>" in text


def test_missing_and_oversized_figures(tmp_path, figure_files, results_factory, monkeypatch):
    figs = dict(figure_files, ghost={"svg": "figures/ghost.svg", "caption": "never drawn"})
    monkeypatch.setattr(H, "_MAX_INLINE_SVG", 100)                # every SVG is "too big"
    text = H.render_html(results_factory(figures=figs), tmp_path).read_text()
    assert "Figure file missing: figures/ghost.svg" in text
    images = Tables(text).images
    assert len(images) == 2 and all(src.startswith("data:image/png;base64,") for src in images)


def test_figures_resolve_against_base_dir(tmp_path, figure_files, results_factory):
    out = tmp_path / "elsewhere"
    text = H.render_html(results_factory(figures=figure_files), out, base_dir=tmp_path).read_text()
    assert len(Tables(text).images) == 2


def test_figure_paths_outside_the_report_folder_are_refused(tmp_path, figure_files, results_factory):
    inside = tmp_path / "report"
    (inside / "figures").mkdir(parents=True)
    secret = tmp_path / "secret.png"
    secret.write_bytes((tmp_path / "figures" / "fig2.png").read_bytes())
    (inside / "figures" / "link.png").symlink_to(secret)
    for path in ("../secret.png", str(secret), "figures/link.png"):
        results = results_factory(figures={"leak": {"png": path, "caption": "c"}})
        with pytest.raises(InputError, match="lies outside the report folder"):
            H.render_html(results, inside / "out", base_dir=inside)
        assert not (inside / "out").exists()
    text = H.render_html(results, inside / "out", base_dir=inside, trusted=True).read_text()
    assert len(Tables(text).images) == 1                # the experiments' own results may share


@pytest.mark.parametrize("value, text", [
    (None, "—"), (True, "yes"), (7000, "7000"), (0.0, "0"), (1234.5, "1234"), (3.14159, "3.14"),
    (0.0123456, "0.0123"), (1.2e-6, "1.20e-06"), (-0.01, "-0.0100"), (2.5e7, "2.50e+07"),
    (float("nan"), "nan"), (float("inf"), "∞"), ({"a": 1, "b": False}, "a: 1; b: no"),
])
def test_fmt(value, text):
    assert H.fmt(value) == text


def test_load_results_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        H.load_results(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="not valid JSON"):
        H.load_results(bad)
    bad.write_text("[1, 2]")
    with pytest.raises(InputError, match="expected a JSON object"):
        H.load_results(bad)


def test_build_report_writes_html_and_a_pdf_with_ink(tmp_path, results_factory, figure_files, pdftoppm):
    (tmp_path / "results.json").write_text(json.dumps(results_factory(figures=figure_files)))
    paths = H.build_report(tmp_path / "results.json", tmp_path / "out")
    assert paths["html"].is_file()
    pdf = paths["pdf"]
    assert pdf == tmp_path / "out" / "report.pdf"
    assert pdf.read_bytes().startswith(b"%PDF") and pdf.stat().st_size > 20_000
    subprocess.run([pdftoppm, "-r", "40", "-png", "-f", "1", "-l", "1", str(pdf),
                    str(tmp_path / "page")], check=True)
    (page,) = tmp_path.glob("page*.png")
    img = mpimg.imread(page)[..., :3]
    assert img.std() > 0.03 and (img < 0.5).mean() > 0.001
    subprocess.run([pdftoppm, "-r", "10", "-png", str(pdf), str(tmp_path / "all")], check=True)
    assert len(list(tmp_path.glob("all*.png"))) >= 3


def test_pdf_of_an_empty_report(tmp_path):
    html = H.render_html({}, tmp_path)
    pdf = H.render_pdf(html, tmp_path / "empty.pdf")
    assert pdf.read_bytes().startswith(b"%PDF")


def test_diverged_values_from_json_render_as_text(tmp_path, results):
    """A diverged baseline (inf/NaN, written by json as Infinity/NaN) is shown as failed runs,
    the others' mean ± std beside it: never a crash, never "∞ ± ∞" (the old robustness cells)."""
    results["accuracy"]["Leaf_1"]["DMP"]["sea"] = {"mean": float("inf"), "std": float("nan")}
    inf = float("inf")
    results["robustness"]["Leaf_2"]["GMR"]["push"]["dtwd_total"] = {
        "mean": inf, "std": inf, "per_demo": [7167.8, inf, 2284.4, inf, 6517.8, 6560.0, inf]}
    results["robustness"]["Leaf_2"]["GMR"]["push"]["goal_error"] = {"mean": inf, "std": inf, "per_demo": [inf, inf]}
    (tmp_path / "r.json").write_text(json.dumps(results))
    text = H.render_html(H.load_results(tmp_path / "r.json"), tmp_path).read_text()
    assert "∞" not in text and "nan" not in text
    assert "<td>failed</td>" in text and "<td>all 2 failed</td>" in text
    assert "<td>5632 ± 1950 (3 of 7 failed)</td>" in text   # the mean and std of the 4 finite values


def test_per_shape_numbers_of_a_finding_become_one_table(tmp_path, results):
    results["findings"] = [{"title": "collapse", "text": "t", "numbers": {
        "Angle: max eig.": -6.69e-05, "Angle: cost ratio": 1.128, "Line: max eig.": -5.4e-05,
        "DTWD identical to SEDS-like": False}}]
    table, other = H.number_table(results["findings"][0]["numbers"])
    assert table == {"columns": ["max eig.", "cost ratio"],
                     "rows": [("Angle", ["-6.69e-05", "1.13"]), ("Line", ["-5.40e-05", "—"])]}
    assert other == [("DTWD identical to SEDS-like", "no")]
    text = H.render_html(results, tmp_path).read_text()
    assert Tables(text).rows[None] == 2
    assert "<th>cost ratio</th>" in text and "DTWD identical to SEDS-like: <b>no</b>" in text


def test_user_report_links_the_benchmark_page_when_it_exists(tmp_path, results):
    (tmp_path / "bench").mkdir()
    (tmp_path / "bench" / "index.html").write_text("<html></html>")
    text = H.render_html(results, tmp_path).read_text()
    assert '<a href="bench/index.html">' in text

"""The benchmark report (sosdyn.report.bench): its own page, from the files the benchmarks wrote."""
import json

from test_html import Tables

from sosdyn.report.bench import render_bench

SUMMARY = "# Benchmarks\n\n| target | result |\n|---|---|\n| fit ≤ 1 s | **missed** |\n\n![K](scaling_K.png)\n\n" \
          "details in [sos.md](sos.md)\n"
PREDICT = {"target_s": 5e-5, "rows": [
    {"shape": "Angle", "K": 6, "n": 2, "field_degree": 1, "predict_s": 2.5457e-4, "predictor_s": 2.2843e-5,
     "speedup": 11.144, "python_export_s": 4.21e-5, "max_rel_diff": 1.897e-14, "within_target": True},
    {"shape": "Angle", "K": 6, "n": 2, "field_degree": 3, "predict_s": 2.74e-4, "predictor_s": 6.1e-5,
     "speedup": 4.49, "max_rel_diff": 4.9e-14, "within_target": False}]}


def test_page_from_summary_predict_and_raw_json(tmp_path):
    (tmp_path / "summary.md").write_text(SUMMARY)
    (tmp_path / "predict.json").write_text(json.dumps(PREDICT))
    (tmp_path / "fits.json").write_text("{}")
    (tmp_path / "scaling_n.md").write_text("## Scaling in n\n\nsee [summary](summary.md)\n")
    text = render_bench(tmp_path).read_text()
    assert '<section id="scaling_n">' in text and "<h2>Scaling in n</h2>" in text and 'href="#summary"' in text
    assert Tables(text).rows["predict-table"] == 2
    assert "<td>254.6 µs</td><td>22.8 µs</td><td>11.1×</td><td>42.1 µs</td><td>1.9e-14</td><td>yes</td>" in text
    assert "<td>61.0 µs</td><td>4.5×</td><td>—</td>" in text and "<td>no</td>" in text
    assert "<th>predictor ≤ 50 µs</th>" in text                   # the target the file was measured against
    assert '<img src="scaling_K.png" alt="K"' in text            # figures stay next to the page
    assert 'href="#sos"' in text and 'href="sos.md"' not in text  # the two summaries link within the page
    assert "Not run (<code>make bench-sos</code>)" in text          # sos.md is missing
    assert 'href="fits.json"' in text and 'href="predict.json"' in text
    assert 'href="../index.html"' in text                           # back to the user report


def test_empty_folder_says_what_to_run(tmp_path):
    text = render_bench(tmp_path).read_text()
    assert text.count("Not run") == 3 and "No JSON files." in text


def test_a_file_already_copied_into_the_summary_is_not_repeated(tmp_path):
    part = "### state dimension n\n\n| n | total |\n|---|---|\n| 2 | 0.77 s |\n"
    (tmp_path / "summary.md").write_text(SUMMARY + "\n" + part)
    (tmp_path / "scaling_n.md").write_text(part)
    (tmp_path / "profile_n7.md").write_text("## cProfile at n = 7\n")
    text = render_bench(tmp_path).read_text()
    assert text.count("<h3>state dimension n</h3>") == 1 and '<section id="scaling_n">' not in text
    assert '<section id="profile_n7">' in text

"""problems.findings: the findings written from the results sections alone; every number the text
quotes is one of its numbers; "the same" has a stated tolerance; failed fits listed, escaped."""
from __future__ import annotations

import pytest

from problems.findings import SAME_RTOL, coincide, default_against_gmr, failures, findings, unquoted
from problems.report_pages import user_report


def _acc(dtwd, certified=None, grid=None):
    return {"dtwd_total": {"mean": dtwd}, "certified": certified, "grid_convergence": grid}


def test_coincide_has_a_stated_tolerance_and_failures_come_from_the_diagnostics():
    sections = {"accuracy": {"A": {"CDSP (paper)": _acc(10.0), "SEDS-like": _acc(10.0 * (1 + SAME_RTOL / 2))},
                             "B": {"CDSP (paper)": _acc(5.0), "SEDS-like": {"certified": False}}},
                "diagnostics": {"B": {"SEDS-like": {"error": "x<y>"}}}}
    assert coincide(sections, "CDSP (paper)", "SEDS-like")
    sections["accuracy"]["A"]["SEDS-like"] = _acc(10.0 * (1 + 2 * SAME_RTOL))
    assert not coincide(sections, "CDSP (paper)", "SEDS-like")
    assert failures(sections) == [("B", "SEDS-like", "x<y>")]
    [failed] = findings(sections)
    assert failed["title"] == "Failed fits (1)" and "x&lt;y&gt;" in failed["text"]


def _gmr_sections():
    """The old Finding 4 quoted only the paper-setting variants (3.1-8.2x GMR) while the default
    on the same page was 0.47-1.84x GMR, lower on 3 of 4 shapes: both must be said."""
    acc = {"A": {"GMR": _acc(100.0, None, 0.0), "CDSP": _acc(47.0, True, 1.0),
                 "CDSP-ICA": _acc(308.0, True, 1.0), "CDSP-cubic": _acc(400.0, True, 1.0)},
           "B": {"GMR": _acc(50.0, None, 0.25), "CDSP": _acc(92.0, True, 1.0), "CDSP-ICA": _acc(411.5, True, 1.0)},
           "C": {"GMR": _acc(10.0, None, 0.0), "CDSP": _acc(8.0, True, 0.96), "CDSP-cubic": _acc(82.3, False, 1.0)}}
    return {"accuracy": acc}


def test_the_default_and_the_paper_variants_against_gmr():
    sections = _gmr_sections()
    rows = {r["shape"]: r for r in default_against_gmr(sections)}
    assert rows["A"]["ratio"] == pytest.approx(0.47) and rows["B"]["ratio"] == pytest.approx(1.84)
    assert rows["A"]["best"] == "CDSP-ICA" and rows["B"]["best_ratio"] == pytest.approx(8.23)
    assert rows["C"]["best"] is None             # an uncertified variant is not "certified"
    [gap] = findings(sections)
    assert "<b>0.470–1.84×</b>" in gap["text"] and "lower on 2 of 3 shapes" in gap["text"]
    assert "certified on 3 of 3" in gap["text"] and "<b>3.08–8.23×</b>" in gap["text"]
    assert "from 96.0–100 % of the grid starts, GMR from 0–25.0 %" in gap["text"]
    assert unquoted(gap["text"], gap["numbers"]) == []
    line, numbers = user_report(sections)
    assert "DTWD 0.470–1.84× GMR's (lower on 2 of 3)" in line
    assert unquoted(line, numbers) == []


def _paper_sections(seds_dtwd):
    acc = {"A": {"CDSP (paper)": _acc(100.0, True), "CDSP-ICA": _acc(50.0, True), "SEDS-like": _acc(seds_dtwd, True)}}
    collapse = {"M(0) certifies": True, "max eig. with M(0)": -5e-5}
    hist = [{"step": "dynamics (M = I)", "cost": 16.0}, {"step": "metric", "cost": 16.0, "margin": 1e-4},
            {"step": "dynamics", "cost": 15.998}]
    ica = [{"step": "dynamics (M = I)", "cost": 16.0}, {"step": "ica", "cost": 10.0}, {"step": "dynamics", "cost": 8.0}]
    return {"accuracy": acc, "certificates": {"A": {"CDSP (paper)": {"metric_collapse": collapse}}},
            "diagnostics": {"A": {"CDSP (paper)": {"final_cost": 15.998, "history": hist},
                                  "CDSP-ICA": {"final_cost": 8.0, "history": ica}}}}


def test_the_same_as_seds_like_is_said_from_the_numbers_with_its_tolerance():
    """The old page printed "identical to SEDS-like: no" beside means equal to 4 parts in 10^5."""
    same, alternation = findings(_paper_sections(100.004))
    assert "are those of <i>SEDS-like</i>" in same["text"] and "by at most 0.00400 %" in same["text"]
    assert same["numbers"]["counted as the same within (%)"] == 100 * SAME_RTOL
    differ, _ = findings(_paper_sections(101.0))
    assert "differs from <i>SEDS-like</i>'s (M = I) by up to 0.990 %" in differ["text"]
    assert alternation["title"] == "Plain alternation stalls; ICA does not"
    assert "lowered the cost by <b>0.0125 %</b>" in alternation["text"] and "by <b>50.0 %</b> in 3 solves" in alternation["text"]
    for f in (same, alternation, differ):
        assert unquoted(f["text"], f["numbers"]) == []


def test_quoted_numbers_are_checked_against_the_numbers():
    assert unquoted("a ratio of <b>3.08–8.23×</b> (mean 5.12×)", {"x: r": 3.0758, "y: r": 8.2288,
                                                                        "z: r": 4.06}) == []
    assert unquoted("a ratio of <b>3.1–8.2×</b>", {"x: r": 0.47, "y: r": 1.84}) == ["3.1", "8.2"]

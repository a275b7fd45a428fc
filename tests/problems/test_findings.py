"""problems.findings: numbers from the entries only; failed fits listed with escaped messages."""
from __future__ import annotations

from problems.findings import coincide, failures, findings


def _ok(dtwd):
    return {"status": "ok", "accuracy": {"dtwd_total": {"mean": dtwd}}}


def test_coincide_and_failures():
    entries = {"A": {"CDSP (paper)": _ok(10.0), "SEDS-like": _ok(10.0 * (1 + 1e-9))},
               "B": {"CDSP (paper)": _ok(5.0), "SEDS-like": {"status": "failed", "error": "x<y>"}}}
    assert coincide(entries, "CDSP (paper)", "SEDS-like")
    entries["A"]["SEDS-like"] = _ok(11.0)
    assert not coincide(entries, "CDSP (paper)", "SEDS-like")
    assert failures(entries) == [("B", "SEDS-like", "x<y>")]
    [failed] = findings(entries)
    assert failed["title"] == "Failed fits (1)" and "x&lt;y&gt;" in failed["text"]


def test_versus_gmr_numbers_read_as_one_row_per_shape():
    def cert(dtwd, grid):
        return {"status": "ok", "diagnostics": {}, "accuracy": {"dtwd_total": {"mean": dtwd}, "certified": True,
                                                                "grid_convergence": grid}}
    entries = {"A": {"GMR": _ok(100.0), "CDSP-ICA": cert(300.0, 1.0), "CDSP-cubic": cert(250.0, 1.0)},
               "B": {"GMR": _ok(50.0), "CDSP-ICA": cert(400.0, 1.0)}}
    entries["A"]["GMR"]["accuracy"]["grid_convergence"] = 0.2
    [gap] = findings(entries)
    assert gap["numbers"] == {"A: best certified method": "CDSP-cubic", "A: its DTWD / GMR's": 2.5,
                              "B: best certified method": "CDSP-ICA", "B: its DTWD / GMR's": 8.0,
                              "A: grid convergence GMR": 0.2}
    assert "<b>2.50–8.00×</b>" in gap["text"] and "GMR from 20.0–20.0 %" in gap["text"]

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

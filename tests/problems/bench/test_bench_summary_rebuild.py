"""problems.bench.learner --summary: summary.md rebuilt from the JSON files of the last runs is
the summary the run wrote; the n-scaling rows carry the core fit and the full default."""
import json

import pytest

pytest.importorskip("SumOfSquares")
pytest.importorskip("pyinstrument")

from problems.bench import learner  # noqa: E402


@pytest.mark.slow
def test_summary_rebuilt_from_json_equals_the_written_one(tmp_path):
    assert learner.main(["--quick", "--out", str(tmp_path)]) == 0
    written = (tmp_path / "summary.md").read_text()
    (tmp_path / "summary.md").unlink()
    assert learner.main(["--out", str(tmp_path), "--summary"]) == 0
    assert (tmp_path / "summary.md").read_text() == written
    scal = json.loads((tmp_path / "scaling_n.json").read_text())
    for r in scal["rows"]:                       # full default (corrective refits) >= its core fit
        assert r["full"] > r["total"] > 0
    assert scal["goals"]["full_ratio"] == pytest.approx(scal["rows"][1]["full"] / scal["rows"][0]["full"])
    assert "core fit (one plain fit: no warp, no corrective refits" in written and "| full default |" in written

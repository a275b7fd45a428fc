"""problems.run: the main job end to end (slow)."""
from __future__ import annotations

import pytest

from problems import run


@pytest.mark.slow
def test_run_quick_paper_shapes(tmp_path):
    assert run.main(["--quick", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "index.html").is_file() and (tmp_path / "report.pdf").stat().st_size > 10_000

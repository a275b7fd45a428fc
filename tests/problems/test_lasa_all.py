"""problems.lasa_all at toy size: two shapes, two methods."""
from __future__ import annotations

import json

import pytest

from problems import lasa_all


@pytest.mark.slow      # experiment-sized: make test-slow
def test_lasa_all_toy(tmp_path, toy_config):
    paths = lasa_all.run(["Leaf_1", "Sine"], ("CDSP-ICA", "GMR"), toy_config, tmp_path, n_jobs=1, K=3,
                         render_pdf=False)
    assert paths["html"].is_file() and (tmp_path / "figures" / "lasa_all.png").is_file()
    res = json.loads((tmp_path / "lasa_all" / "results.json").read_text())
    assert set(res["accuracy"]) == {"Leaf_1", "Sine"}
    assert res["figures"]["lasa_all"]["png"] == "../figures/lasa_all.png"

"""problems.demo3d: the 3-D demonstrations load and the experiment writes its figure."""
from __future__ import annotations

import json
import math

from problems import demo3d


def test_demo3d_data_and_experiment(tmp_path):
    demos = demo3d.load()
    assert len(demos) == 4 and demos.dim == 3 and all(100 <= len(d.t) <= 1000 for d in demos)
    spec = demo3d.run(tmp_path, quick=True, methods=("CDSP-ICA",), n_demos=2, subsample=3)
    assert (tmp_path / spec["demo3d"]["png"]).is_file()
    res = json.loads((tmp_path / "demo3d.json").read_text())
    assert math.isfinite(res["CDSP-ICA"]["dtwd_total"]["mean"])

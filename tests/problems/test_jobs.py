"""problems.jobs: worker processes return results in input order."""
from __future__ import annotations

import math


from problems.jobs import _job, parallel_map


def test_clfdm_and_parallel_map(tmp_path, toy_shape, toy_config):
    e = parallel_map(_job, [(toy_shape, "CLF-DM", True, toy_config, tmp_path, False)], n_jobs=2, progress=False)[0]
    assert e["status"] == "ok" and math.isfinite(e["accuracy"]["dtwd_total"]["mean"])
    out = parallel_map(pow, [(2, 3), (3, 2), (4, 1)], n_jobs=2, progress=False)
    assert out == [8, 9, 4]

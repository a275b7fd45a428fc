"""problems.demo7d: the ground truth is contracting, and a quick 7-D fit is certified and
reproduces the noisy demonstrations to within a few noise levels."""
from __future__ import annotations

import json

import numpy as np

from problems import demo7d


def test_ground_truth_is_a_contracting_flow_seen_through_a_diffeomorphism():
    field, to_joints = demo7d.truth(0)
    rng = np.random.default_rng(3)
    for y in rng.normal(size=(20, demo7d.N)):
        h = 1e-6
        J = np.array([(field(y + h * e) - field(y - h * e)) / (2 * h) for e in np.eye(demo7d.N)]).T
        assert np.linalg.eigvalsh(0.5 * (J + J.T)).max() <= -0.6 + 1e-6      # -D + skew - 0.3 y^2
        Jmap = np.array([(to_joints(y + h * e) - to_joints(y - h * e)) / (2 * h) for e in np.eye(demo7d.N)]).T
        assert np.linalg.svd(Jmap / demo7d.SCALE, compute_uv=False).min() >= 1 - 0.3 - 1e-6
    np.testing.assert_allclose(to_joints(np.zeros(demo7d.N)), demo7d.GOAL)


def test_quick_demo7d_fit_is_certified_and_close_to_the_demonstrations(tmp_path):
    res = demo7d.run(tmp_path, quick=True)
    assert res["certified"] and res["dimension"] == 7 and res["demos"] == 3
    assert res["mean_rmse_rad"] < 5 * demo7d.NOISE                # a few noise levels (0.002 rad)
    assert res["max_final_goal_error_rad"] < 0.05
    saved = json.loads((tmp_path / "demo7d.json").read_text())
    assert saved["mean_rmse_rad"] == res["mean_rmse_rad"]
    assert (tmp_path / "demo7d.png").stat().st_size > 10_000

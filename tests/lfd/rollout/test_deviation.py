"""sosdyn.lfd.rollout.quality.deviation: each point's distance to the nearest point of a path,
against the dense distance matrix (scipy's cdist)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from sosdyn.lfd.rollout.quality import deviation


def test_deviation_is_the_nearest_distance_of_the_dense_matrix():
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 7):
        demo, path = rng.normal(size=(300, n)), rng.normal(size=(2000, n))
        np.testing.assert_allclose(deviation(demo, path), cdist(demo, path).min(axis=1), rtol=1e-12, atol=0)
    assert deviation(np.zeros((2, 2)), np.array([[3.0, 4.0]])).tolist() == [5.0, 5.0]

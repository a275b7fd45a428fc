"""sosdyn.lfd.model.reach: the box a certified trajectory never leaves, and its excursion bound."""
from types import SimpleNamespace

import numpy as np
import pytest

from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.reach import reach_box, warp_shift
from sosdyn.lfd.rollout.quality import box_excursion, excursion


def test_box_excursion_known_answers():
    lo, hi = np.zeros(2), np.ones(2)                         # diagonal sqrt 2
    assert box_excursion(np.array([-1.0, -1.0]), np.array([2.0, 2.0]), lo, hi)[0] == pytest.approx(1.0)
    assert box_excursion(np.array([0.2, 0.2]), np.array([0.8, 0.9]), lo, hi)[0] == 0.0
    # per coordinate the larger side counts: x exceeds by 3 on the left, y by 4 on the top
    assert box_excursion(np.array([-3.0, 0.5]), np.array([1.5, 5.0]), lo, hi)[0] == pytest.approx(5 / np.sqrt(2))
    corners = np.array([[-3.0, 5.0]])                        # the box's worst point: the bound is attained
    assert box_excursion(np.array([-3.0, 0.5]), np.array([1.5, 5.0]), lo, hi)[0] == excursion(corners, lo, hi)


def test_warp_shift_of_one_bump():
    """psi(z) = z + (rho(z) - rho(0)) v, rho(0) = e^{-1} for a centre at distance sigma: z - psi(z) in
    [-(1 - e^{-1}) v, e^{-1} v] per coordinate (v = (2, -1))."""
    e = np.exp(-1.0)
    lo, hi = warp_shift(np.array([[1.0, 0.0]]), np.array([[2.0, -1.0]]), np.array([1.0]))
    assert np.allclose(lo, [-2 * (1 - e), -e]) and np.allclose(hi, [2 * e, 1 - e])


def test_reach_box_of_a_constant_metric_known_answer():
    """M = diag(4, 1), goal 0, scale 2, start x0 = (2, 2): z0 = (1, 1), V0 = 5, r = (sqrt(5/4), sqrt 5)."""
    model = SimpleNamespace(W_=np.diag([4.0, 1.0])[:, :, None], metric_exps_=np.zeros((1, 2), dtype=np.int64),
                            dim_=2, goal_=np.zeros(2), scale_=2.0, warp_=None)
    lo, hi = reach_box(model, np.array([[2.0, 2.0]]))
    assert np.allclose(hi, [2 * np.sqrt(1.25), 2 * np.sqrt(5.0)]) and np.allclose(lo, -hi)
    model.W_ = np.stack([np.diag([4.0, 1.0]), np.eye(2)], axis=2)     # M(z) = diag(4, 1) + z_1^2 I: no bound
    model.metric_exps_ = np.array([[0, 0], [2, 0]])
    assert reach_box(model, np.array([[2.0, 2.0]])) is None


@pytest.mark.parametrize("warp", ["none", {"n_maps": 30, "decay": 1.0}])
def test_rollouts_stay_in_their_reach_box(leaf, warp):
    """Certified fits of Leaf_1 (plain and warped): rollouts from the demos' starts and from starts
    pushed 50 % further from the goal stay inside the box reach_box gives for their start."""
    model = CDSP(n_components=3, warp=warp, max_iter=3, max_samples=300, corrective_rounds=0).fit(leaf[:3])
    assert model.certified_ and (model.warp_ is not None) == (warp != "none")
    starts = np.array([d.pos[0] for d in leaf[:3]])
    starts = np.vstack([starts, model.goal_ + 1.5 * (starts - model.goal_)])
    lo, hi = reach_box(model, starts)
    reached = []
    for x0, a, b in zip(starts, lo, hi):
        path = model.rollout(x0, duration=10.0).pos
        slack = 1e-9 * model.scale_
        assert (path >= a - slack).all() and (path <= b + slack).all()
        assert np.all(a <= x0) and np.all(x0 <= b)
        reached.append(np.abs(path - model.goal_).max(axis=0) / np.maximum(b - model.goal_, model.goal_ - a))
    assert 0.3 < np.max(reached) <= 1.0              # a bound, and not a vacuous one

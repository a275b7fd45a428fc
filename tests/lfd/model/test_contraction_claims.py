"""What the certificate proves, measured (issue 23, item 7; docs/theory.md, "What the certificate
proves, and what it does not"): every trajectory's distance to the goal in the certificate's metric
shrinks at least as fast as e^{-gamma t / 2}; two nearby trajectories may move apart."""
import numpy as np
import pytest

from sosdyn.lfd.fit.composite import jacobian
from sosdyn.lfd.model.cdsp import CDSP

# Without the speed floor (a time change: the pairs' mutual distance at equal times changes with it; with
# the floor the unwarped pair's growth is 1.43x, the warped one has none).
SMALL = {"n_components": 3, "max_samples": 300, "verify_samples": 500, "speed_floor": "none"}
# Per warp setting: the start pair, 1 % of the data box's diagonal apart, of largest separation among
# 40 random pairs in the box (seed 0), its measured growth (at t = 1.97 s / 0.62 s; the red team's
# pair: 3.67x / 2.08x; the warped pair's is 2.15x with gating="posterior", 1.95x at 0.63 s with the
# tempered weights of gating="tempered" and of the default "smooth", which it never leaves: it starts off
# the data) and the rollouts' duration.
PAIRS = {"none": ((0.7401241, 0.57046346), (0.74114245, 0.61203197), 6.86, 4.0),
         "warped": ((-1.7782165, 1.67654057), (-1.76642324, 1.63666706), 1.95, 1.5)}


def certificate_coordinates(model, X):
    """u = phi(z), z = (x - goal) / scale: where the certified system u' = sum_k h_k(u) f_k(u) lives
    (u = z without a warp); its metric M is constant here (metric_degree = 0)."""
    Z = (X - model.goal_) / model.scale_
    return Z if model.warp_ is None else jacobian(Z, model.warp_)[0]


@pytest.fixture(scope="module", params=list(PAIRS))
def measured(request, hook_demos):
    model = CDSP(**SMALL, warp="none" if request.param == "none" else {}).fit(hook_demos)
    assert model.certified_ and model.metric_exps_.shape == (1, 2) and not model.metric_exps_.any()
    M = model.W_[:, :, 0]
    a, b, growth, duration = PAIRS[request.param]
    runs = [model.rollout(np.array(x0), duration, dt=0.01) for x0 in (a, b)]
    U = [certificate_coordinates(model, r.pos) for r in runs]
    norm = lambda V: np.sqrt(np.einsum("ti,ij,tj->t", V, M, V))      # noqa: E731
    return model, runs[0].t, [norm(u) for u in U], norm(U[0] - U[1]), growth


def test_every_trajectory_approaches_the_goal_at_the_certified_rate(measured):
    model, t, to_goal, _, _ = measured
    for d in to_goal:
        bound = d[0] * np.exp(-model.gamma * t / 2)
        assert np.all(d <= bound * (1 + 1e-5) + 1e-9)       # rollout rtol 1e-6
        assert d[-1] < 0.9 * d[0]                            # and it has moved in


def test_nearby_trajectories_need_not_approach_each_other(measured):
    """The mutual M-distance grows to 6.86x (no warp) / 1.95x (warp) its start: no contraction of
    the model itself. It stays below the triangle bound through the goal."""
    model, t, to_goal, apart, growth = measured
    assert apart.max() / apart[0] == pytest.approx(growth, rel=0.01)
    assert np.all(apart <= (to_goal[0][0] + to_goal[1][0]) * np.exp(-model.gamma * t / 2) * (1 + 1e-5))

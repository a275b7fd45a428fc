"""GMR baseline: known answers on linear data, the shared GMM maps, typed errors."""

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.stats import multivariate_normal
from sklearn.mixture import GaussianMixture

from sosdyn.errors import InputError, NotFittedError
from sosdyn.evaluation.baselines import GMR, gmm_linear_maps, position_responsibilities
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations

GOAL = np.array([1.0, 2.0])
A_STABLE = np.array([[-1.0, 0.8], [-0.3, -1.5]])


@pytest.fixture(scope="module")
def linear_demos():
    """Five exact solutions of ẋ = A(x − g) from starts on a circle of radius 4 around g."""
    t = np.linspace(0.0, 6.0, 301)
    demos = []
    for angle in np.linspace(0.0, 2 * np.pi, 5, endpoint=False):
        e0 = 4.0 * np.array([np.cos(angle), np.sin(angle)])
        err = np.array([expm(A_STABLE * s) @ e0 for s in t])
        demos.append(Demonstration(t, GOAL + err, err @ A_STABLE.T))
    return Demonstrations(demos, "linear", "m")


def _mixture(means, covariances, weights):
    """A GaussianMixture with the given parameters, without fitting."""
    gmm = GaussianMixture(n_components=len(weights), covariance_type="full")
    gmm.means_, gmm.covariances_, gmm.weights_ = means, covariances, weights
    return gmm


def test_gmr_learns_a_stable_linear_system(linear_demos):
    model = GMR(n_components=3).fit(linear_demos)
    rng = np.random.default_rng(0)
    X = GOAL + rng.uniform(-3.0, 3.0, size=(200, 2))
    expected = (X - GOAL) @ A_STABLE.T
    error = np.linalg.norm(model.predict(X) - expected, axis=1)
    assert error.max() < 1e-3 * np.linalg.norm(expected, axis=1).max()
    np.testing.assert_allclose(model.A_, np.broadcast_to(A_STABLE, (3, 2, 2)), atol=2e-2)
    np.testing.assert_allclose(model.b_, np.broadcast_to(-A_STABLE @ GOAL, (3, 2)), atol=5e-2)
    trajectory = model.rollout([4.0, -1.0], 10.0, dt=0.05)
    assert np.linalg.norm(trajectory.pos[-1] - GOAL) < 1e-3


def test_gmm_linear_maps_known_single_component():
    A = np.array([[-2.0, 1.0], [0.5, -3.0]])
    mu_x, b = np.array([0.3, -0.7]), np.array([1.0, 2.0])
    S_xx = np.array([[2.0, 0.4], [0.4, 1.0]])
    cov = np.block([[S_xx, S_xx @ A.T], [A @ S_xx, A @ S_xx @ A.T + 0.1 * np.eye(2)]])
    gmm = _mixture(np.array([np.r_[mu_x, A @ mu_x + b]]), cov[None], np.array([1.0]))
    A_k, b_k = gmm_linear_maps(gmm, 2)
    np.testing.assert_allclose(A_k[0], A, atol=1e-12)
    np.testing.assert_allclose(b_k[0], b, atol=1e-12)


def test_position_responsibilities_match_bayes_rule_and_stay_finite_far_away():
    means = np.array([[0.0, 0.0, 1.0, 1.0], [3.0, 1.0, -1.0, 0.0]])
    covs = np.array([np.eye(4), np.diag([0.5, 2.0, 1.0, 1.0])])
    gmm = _mixture(means, covs, np.array([0.3, 0.7]))
    X = np.array([[0.5, 0.2], [2.0, 1.0], [1.5, -0.5]])
    dens = np.column_stack([w * multivariate_normal(m[:2], c[:2, :2]).pdf(X)
                            for w, m, c in zip(gmm.weights_, means, covs)])
    np.testing.assert_allclose(position_responsibilities(gmm, X, 2),
                               dens / dens.sum(axis=1, keepdims=True), rtol=1e-12)
    far = position_responsibilities(gmm, np.array([[1e4, -1e4]]), 2)   # every pdf underflows
    assert np.all(np.isfinite(far)) and np.isclose(far.sum(), 1.0)


def test_goal_change_translates_the_field(linear_demos):
    model = GMR(n_components=2).fit(linear_demos)
    X, new_goal = np.array([[0.0, 0.0], [2.0, 5.0]]), np.array([-3.0, 4.0])
    np.testing.assert_allclose(model.field(X, new_goal), model.predict(X - new_goal + GOAL))
    assert model.responsibilities(X).shape == (2, 2)


def test_bad_inputs_raise_typed_errors(linear_demos):
    with pytest.raises(NotFittedError, match="fit"):
        GMR().predict(np.zeros((1, 2)))
    with pytest.raises(InputError, match="n_components"):
        GMR(n_components=0).fit(linear_demos)
    with pytest.raises(InputError):
        GMR().fit("Leaf_1")
    model = GMR(n_components=2).fit(linear_demos)
    with pytest.raises(InputError, match=r"shape \(m, 2\)"):
        model.predict(np.zeros((4, 3)))
    with pytest.raises(InputError, match="NaN"):
        model.predict([[np.nan, 0.0]])
    with pytest.raises(InputError, match="x0"):
        model.rollout([0.0, 0.0, 0.0], 1.0)
    with pytest.raises(InputError, match="duration"):
        model.rollout([0.0, 0.0], -1.0)
    with pytest.raises(InputError, match="2\\*n"):
        gmm_linear_maps(model.gmm_, 3)

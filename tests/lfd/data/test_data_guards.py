"""Guards far from the data: responsibilities (sosdyn.lfd.fit.gmm) and a fitted model's predict and
rollout there (sosdyn.lfd.model.cdsp)."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

import sosdyn as sd
from sosdyn.errors import InputError, ResourceLimitError
from sosdyn.lfd.fit.gmm import PositionMixture

# ---------------------------------------------------------------- responsibilities far from the data


def two_gaussians(weights=(0.5, 0.5)):
    return PositionMixture(np.array(weights), np.array([[0.0, 0.0], [10.0, 0.0]]),
                           np.array([np.eye(2), 4 * np.eye(2)]))


def test_responsibilities_equal_the_density_ratio_near_the_data():
    mix = two_gaussians((0.3, 0.7))
    X = np.array([[0.0, 0.0], [5.0, 1.0], [12.0, -3.0], [-4.0, 2.0]])
    dens = np.column_stack([w * multivariate_normal(m, c).pdf(X)
                            for w, m, c in zip(mix.weights, mix.means, mix.covariances)])
    np.testing.assert_allclose(mix.responsibilities(X), dens / dens.sum(axis=1, keepdims=True), rtol=1e-12)


def test_far_from_the_data_the_mahalanobis_nearest_component_takes_all():
    mix = two_gaussians((0.99, 0.01))     # component 1 is wider: nearest in Mahalanobis distance far away
    X = np.array([[1e150, 0.0], [1e160, 0.0], [-1e300, 5.0], [1.7e308, -1.7e308], [0.0, -1e200]])
    h = mix.responsibilities(X)
    np.testing.assert_array_equal(h, np.tile([0.0, 1.0], (5, 1)))
    thin = PositionMixture(np.array([0.5, 0.5]), np.zeros((2, 2)), np.array([np.diag([100.0, 0.01]), np.eye(2)]))
    np.testing.assert_array_equal(thin.responsibilities(np.array([[1e200, 0.0], [0.0, 1e200]])), [[1, 0], [0, 1]])
    np.testing.assert_allclose(thin.log_mahalanobis(np.array([[1e200, 0.0]])), [[np.log(1e199), np.log(1e200)]])


def test_responsibilities_refuse_nan_rows():
    with pytest.raises(InputError, match=r"row 1 = \[nan  0\.\] is not finite"):
        two_gaussians().responsibilities(np.array([[0.0, 0.0], [np.nan, 0.0]]))


# ---------------------------------------------------------------- a fitted model far away


def line_demos(n=2):
    t = np.linspace(0, 3, 60)
    demos = [sd.Demonstration(t, np.outer(np.exp(-t), s), -np.outer(np.exp(-t), s))
             for s in ([5.0, 3.0], [-4.0, 6.0], [3.0, -5.0])]
    return sd.Demonstrations(demos, "lines", "m")


@pytest.fixture(scope="module")
def linear_model():
    return sd.CDSP(n_components=2, gamma=0.5, warp="none").fit(line_demos())


@pytest.fixture(scope="module")
def cubic_model():
    return sd.CDSP(n_components=1, gamma=0.5, field_degree=3, warp="none").fit(line_demos())


def test_predict_far_away_is_finite_or_a_typed_error(linear_model, cubic_model):
    for x in (1e160, 1e300):
        v = linear_model.predict([x, -x])
        assert np.isfinite(v).all() and np.abs(v).max() > 0.1 * x      # xdot ~ -x: it points home
    assert np.isfinite(cubic_model.predict([1e50, -1e50])).all()
    with pytest.raises(InputError, match=r"overflows.*Try:"):
        cubic_model.predict([1e160, -1e160])


def test_model_rollout_dt_and_size(linear_model):
    with pytest.raises(ResourceLimitError, match="max_rollout_steps"):
        linear_model.rollout([1.0, 1.0], duration=1e9)
    with pytest.raises(InputError, match="dt must be a finite number > 0"):
        linear_model.rollout([1.0, 1.0], duration=1.0, dt=0)
    traj = linear_model.rollout([1.0, 1.0], duration=np.float32(0.5))
    np.testing.assert_allclose(np.diff(traj.t).mean(), linear_model.dt_, rtol=0.1)

"""CLF-DM baseline: exact objective gradient, learned energy, the online correction."""

import numpy as np
import pytest
from scipy.optimize import approx_fprime

from sosdyn.errors import InputError
from sosdyn.evaluation.baselines import CLFDM, fit_wsaqf
from sosdyn.evaluation.baselines.clfdm import wsaqf_objective
from sosdyn.lfd.rollout import rollout


def test_objective_gradient_matches_finite_differences():
    rng = np.random.default_rng(1)
    Z, V = rng.normal(size=(200, 2)), rng.normal(size=(200, 2))
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    theta = 0.5 * rng.normal(size=4 * 3 + 3 * 2)               # L = 3
    value, gradient = wsaqf_objective(theta, Z, V, 3, 0.1)
    numeric = approx_fprime(theta, lambda th: wsaqf_objective(th, Z, V, 3, 0.1)[0], 1e-7)
    np.testing.assert_allclose(gradient, numeric, atol=1e-6 * np.abs(numeric).max())


def test_learned_wsaqf_descends_along_most_leaf_1_data(leaf_1):
    X, Xdot = leaf_1.subsample(5).stacked()
    energy = fit_wsaqf(X - leaf_1.goal, Xdot, n_asymmetric=6, n_init=3)
    X, Xdot = leaf_1.stacked()
    moving = np.linalg.norm(Xdot, axis=1) > 0
    descent = np.sum(energy.gradient(X - leaf_1.goal) * Xdot, axis=1)[moving] < 0
    assert descent.mean() > 0.85                                  # measured 0.92
    assert np.all(np.linalg.eigvalsh(energy.P) > 0)
    assert energy.value(np.zeros((1, 2)))[0] == 0.0


@pytest.fixture(scope="module")
def straight_model(straight_demos):
    return CLFDM(n_components=2, n_asymmetric=1, n_init=2).fit(straight_demos)


def test_correction_makes_an_unstable_nominal_field_converge(straight_demos, straight_model):
    model, goal = straight_model, straight_demos.goal
    for demo in straight_demos:
        x0 = demo.pos[0]
        nominal = rollout(model.nominal_field, x0, duration=30.0, dt=0.05, goal=goal)
        corrected = model.rollout(x0, 30.0, dt=0.05)
        assert np.linalg.norm(nominal.pos[-1] - goal) > 3.0       # nominal runs through the goal
        assert np.linalg.norm(corrected.pos[-1] - goal) < 0.1     # 2 % of the 5 m reach
        energy = model.energy(corrected.pos)
        assert np.all(np.diff(energy) <= 1e-9 * energy[0])         # V never increases
        changed = np.linalg.norm(model.field(corrected.pos, goal)
                                 - model.nominal_field(corrected.pos, goal), axis=1) > 1e-9
        assert changed.any()                                        # the correction acted


def test_goal_change_shifts_the_coordinates(straight_demos, straight_model):
    model, goal = straight_model, straight_demos.goal
    new_goal = goal + np.array([2.0, -1.0])
    X = np.array([[0.0, 0.0], [3.0, 4.0]])
    np.testing.assert_allclose(model.field(X, new_goal), model.predict(X - new_goal + goal))
    trajectory = model.rollout(straight_demos[1].pos[0], 40.0, dt=0.05,
                               goal_changes=[(2.0, new_goal)])
    assert np.linalg.norm(trajectory.pos[-1] - new_goal) < 0.1


def test_bad_hyper_parameters_raise_typed_errors(straight_demos):
    with pytest.raises(InputError, match="w must"):
        CLFDM(w=2.0).fit(straight_demos)
    with pytest.raises(InputError, match="n_asymmetric"):
        CLFDM(n_components=2, n_asymmetric=-1).fit(straight_demos)
    with pytest.raises(InputError, match="rho0"):
        CLFDM(n_components=2, n_asymmetric=1, rho0=-1.0).fit(straight_demos)

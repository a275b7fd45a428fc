"""DynamicsStep: least squares under SOS contraction for a fixed metric."""
import numpy as np
import pytest

from sosdyn.lfd.contraction import field_exponents, margin_degree, metric_exponents, state_variables
from sosdyn.lfd.steps import DynamicsStep, LeastSquaresData

A_IN = np.array([[-1.0, 0.5], [-0.5, -2.0]])      # A + A^T < 0: contracts in the identity metric
A_OUT = np.array([[-1.0, 4.0], [0.0, -1.0]])      # A + A^T has eigenvalue +2: does not


def linear_data(A, T=200):
    Z = np.random.default_rng(0).uniform(-1, 1, size=(T, 2))
    return LeastSquaresData(np.ones((T, 1)), Z, Z @ A.T)


@pytest.fixture(scope="module")
def step():
    return DynamicsStep(linear_data(A_IN), field_exponents(2, 1), metric_exponents(2, 0), state_variables(2),
                        gamma=0.1, margin=1e-4)


def test_a_field_that_contracts_in_the_metric_is_recovered(step):
    C, sol = step.solve(np.eye(2)[:, :, None])
    np.testing.assert_allclose(C[0], A_IN, atol=1e-5)
    assert sol.status == "optimal" and step.data.cost(C) < 1e-9


def test_the_constraint_binds_for_a_field_that_does_not(step):
    C, _ = step.refit(linear_data(A_OUT))
    G = C[0] + C[0].T + 0.1 * np.eye(2)
    assert np.linalg.eigvalsh(G).max() <= -1e-4 + 1e-7        # -G - margin I >= 0 (solver accuracy)
    assert step.data.cost(C) > 0.1


def test_weights_are_named_by_unit_metric_and_margin_degree(step):
    W = np.array([[2.0, 0.5], [0.5, 3.0]])[:, :, None]
    named = step.weights(W, 1e-4, margin_degree(W, step.mexps, step.fexps))
    assert named == {("metric", 0, 0, 0): 2.0, ("metric", 0, 1, 0): 0.5, ("metric", 1, 1, 0): 3.0,
                     ("margin", 0): 1e-4}
    assert step.tables[0].names == tuple(named)

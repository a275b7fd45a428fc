"""DynamicsStep: least squares under SOS contraction for a fixed metric."""
import numpy as np
import pytest

from sosdyn.lfd.fit.contraction import (contraction_polymatrix, decision_fields, field_exponents, margin_degree,
                                    metric_exponents, state_variables, unit_metrics)
from sosdyn.lfd.fit.steps import DynamicsStep, LeastSquaresData
from sosdyn.poly import monomial_values

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
    assert sol.usable and step.data.cost(C) < 1e-9


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


def test_every_component_has_component_zeros_terms_with_its_own_ids():
    """Components k > 0 get component 0's terms with the ids renamed: exactly the matrices the
    polynomial algebra gives for their own decision fields (cubic fields, degree-2 metric)."""
    n, K = 2, 3
    fexps, mexps, vars = field_exponents(n, 3), metric_exponents(n, 2), state_variables(n)
    Z = np.random.default_rng(1).uniform(-1, 1, size=(40, n))
    data = LeastSquaresData(np.full((40, K), 1.0 / K), monomial_values(Z, fexps), -Z)
    step = DynamicsStep(data, fexps, mexps, vars, gamma=0.1, margin=1e-4)
    fields = decision_fields(step.ids.reshape(K, n, -1), fexps, vars)
    units = dict(unit_metrics(mexps, n, vars))
    for k in (1, 2):
        table = step.tables[k]
        for name, T in zip(table.names, table.terms):
            if name[0] != "metric":
                continue
            want = contraction_polymatrix(fields[k], units[name[1:]], vars, 0.1, scale=-1.0)
            for got, ref in zip(T.entries.flat, want.entries.flat):
                assert np.array_equal(got.ids, ref.ids) and np.array_equal(got.coef, ref.coef)
                assert np.array_equal(got.exps, ref.exps)
    assert len(step.tables[2].names) == 3 * mexps.shape[0] + len(step.grow_degrees)

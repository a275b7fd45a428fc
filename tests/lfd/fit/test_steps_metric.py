"""MetricStep: the metric with the largest contraction margin for fixed fields."""
import numpy as np
import pytest

from sosdyn.lfd.fit.contraction import field_exponents, metric_exponents, state_variables
from sosdyn.lfd.fit.steps import MetricStep

A = np.array([[-1.0, 4.0], [0.0, -1.0]])           # contracts only in a non-identity metric


def test_finds_a_metric_the_identity_is_not():
    met = MetricStep(2, 1, metric_exponents(2, 0), field_exponents(2, 1), state_variables(2), gamma=0.1,
                     eps=1e-3, grow_degree=0)
    W, t, sol = met.solve(A[None])
    P = W[:, :, 0]
    assert sol.usable and t > 0.05
    assert np.isclose(np.trace(P), 2.0) and np.linalg.eigvalsh(P)[0] >= 1e-3 - 1e-8
    G = A.T @ P + P @ A + 0.1 * P
    assert np.linalg.eigvalsh(G).max() <= -t + 1e-6              # -G - t I >= 0
    assert met.table.names[-1] == "fixed" and met.table.names[0] == ("field", 0, 0)


def test_no_metric_makes_an_expanding_field_contract():
    met = MetricStep(2, 1, metric_exponents(2, 0), field_exponents(2, 1), state_variables(2), gamma=0.1,
                     eps=1e-3, grow_degree=0)
    _, t, _ = met.solve(np.eye(2)[None])                          # f = z: trace(G) > 0 for any P
    assert t <= 1e-9


# A fast field (A = -50 I): every metric with lambda_min(P) >= t_max / (100 - gamma) reaches the
# margin bound t_max = 10, so the plain step's maximiser is a whole face. The proximal step
# (maximise t - rho |w - w0|^2) picks the point of that face closest to the current metric:
# the current metric itself when it is on the face.
FAST = -50.0 * np.eye(2)


def _step():
    return MetricStep(2, 1, metric_exponents(2, 0), field_exponents(2, 1), state_variables(2), gamma=0.1,
                      eps=1e-3, grow_degree=0)


def test_proximal_step_keeps_an_optimal_current_metric():
    P0 = np.array([[1.2, 0.3], [0.3, 0.8]])                       # trace 2, lambda_min 0.64 > 10/99.9
    W, t, _ = _step().solve(FAST[None], P0[:, :, None], prox=1e-2)
    assert t == pytest.approx(10.0, abs=1e-6)
    assert np.abs(W[:, :, 0] - P0).max() < 1e-5


def test_proximal_step_is_stable_under_a_tiny_perturbation():
    # A field that contracts in many metrics (the t_max face) and a start off that face.
    A = np.array([[-1.0, 4.0], [0.0, -1.0]])
    P0 = np.eye(2)
    step = _step()
    W1, t1, _ = step.solve(A[None], P0[:, :, None], prox=1e-2)
    W2, t2, _ = step.solve((A + 1e-10)[None], P0[:, :, None], prox=1e-2)
    assert t1 > 0.05 and abs(t1 - t2) < 1e-6
    assert np.abs(W1 - W2).max() < 1e-5
    # and the proximal answer is still certified: -G - t I >= 0 with trace P = 2
    P = W1[:, :, 0]
    assert np.trace(P) == pytest.approx(2.0) and np.linalg.eigvalsh(A.T @ P + P @ A + 0.1 * P).max() <= -t1 + 1e-6

"""MetricStep: the metric with the largest contraction margin for fixed fields."""
import numpy as np

from sosdyn.lfd.contraction import field_exponents, metric_exponents, state_variables
from sosdyn.lfd.steps import MetricStep

A = np.array([[-1.0, 4.0], [0.0, -1.0]])           # contracts only in a non-identity metric


def test_finds_a_metric_the_identity_is_not():
    met = MetricStep(2, 1, metric_exponents(2, 0), field_exponents(2, 1), state_variables(2), gamma=0.1,
                     eps=1e-3, grow_degree=0)
    W, t, sol = met.solve(A[None])
    P = W[:, :, 0]
    assert sol.status == "optimal" and t > 0.05
    assert np.isclose(np.trace(P), 2.0) and np.linalg.eigvalsh(P)[0] >= 1e-3 - 1e-8
    G = A.T @ P + P @ A + 0.1 * P
    assert np.linalg.eigvalsh(G).max() <= -t + 1e-6              # -G - t I >= 0
    assert met.table.names[-1] == "fixed" and met.table.names[0] == ("field", 0, 0)


def test_no_metric_makes_an_expanding_field_contract():
    met = MetricStep(2, 1, metric_exponents(2, 0), field_exponents(2, 1), state_variables(2), gamma=0.1,
                     eps=1e-3, grow_degree=0)
    _, t, _ = met.solve(np.eye(2)[None])                          # f = z: trace(G) > 0 for any P
    assert t <= 1e-9

"""ICAStep: every iterate is certified and the cost does not increase."""
import numpy as np

from sosdyn.lfd.contraction import field_exponents, metric_exponents, state_variables
from sosdyn.lfd.steps import DynamicsStep, ICAStep, LeastSquaresData

A = np.array([[-1.0, 4.0], [0.0, -1.0]])


def test_ica_iterates_stay_certified_and_lower_the_cost():
    Z = np.random.default_rng(0).uniform(-1, 1, size=(200, 2))
    data = LeastSquaresData(np.ones((200, 1)), Z, Z @ A.T)
    fexps, vars = field_exponents(2, 1), state_variables(2)
    C, _ = DynamicsStep(data, fexps, metric_exponents(2, 0), vars, 0.1, 1e-4).solve(np.eye(2)[:, :, None])
    ica = ICAStep(data, fexps, vars, gamma=0.1, margin=1e-4, eps=1e-3)
    P, costs = np.eye(2), [data.cost(C)]
    for _ in range(4):
        C, P, sol = ica.solve(C, P)
        costs.append(data.cost(C))
        G = C[0].T @ P + P @ C[0] + 0.1 * P
        assert sol.status == "optimal" and np.isclose(np.trace(P), 2.0)
        assert np.linalg.eigvals(np.linalg.solve(P, G)).real.max() < 0
    assert all(b <= a + 1e-9 for a, b in zip(costs, costs[1:])) and costs[-1] < 0.5 * costs[0]
    names = ica.tables[0].names
    assert names[:3] == ("own", "margin", ("J P0", (0, 0))) and names[-2:] == ("1/a", "a")

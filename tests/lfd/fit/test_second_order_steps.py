"""The second-order fit's convex steps: every iterate certified, the cost never increasing, and the
exact check agreeing with the eigenvalues."""
import numpy as np
import pytest

from sosdyn.lfd.fit.second_order.core import companion, fit_gating, lmi, metric_step, nominal_fields, scaled_samples
from sosdyn.lfd.fit.second_order.certificate import exact_lmis
from sosdyn.lfd.fit.second_order.learner import METHODS, fit_second_order, lmi_margin
from sosdyn.sos.gram import proven_min_eig


def test_nominal_metric_certifies_the_critically_damped_system():
    M, t = metric_step(nominal_fields(2, 3, 2.0), 0.5)
    assert np.trace(M) == pytest.approx(4.0) and t > 0
    assert lmi_margin(nominal_fields(2, 3, 2.0), M, 0.5) == pytest.approx(t, rel=1e-4)
    # the rate cannot reach w = 2 (a double eigenvalue -2): the margin at gamma' = 1.9 is far smaller
    assert metric_step(nominal_fields(2, 1, 2.0), 1.9)[1] < 0.1 * t


@pytest.mark.parametrize("method", METHODS)
def test_every_iterate_is_certified_and_the_cost_never_increases(method, second_order_system):
    sc = scaled_samples(second_order_system[3], 2, 600)
    mix = fit_gating(sc.E, 2, 0)
    fit = fit_second_order(sc, mix, 0.1, 1e-4, 4, 1e-6, method=method)
    costs = [h["cost"] for h in fit.history]
    assert all(b <= a * (1 + 1e-9) for a, b in zip(costs, costs[1:])) and costs[-1] < costs[0]
    g = 0.1 * sc.time
    assert fit.margin > 0 and lmi_margin(fit.C, fit.M, g) == pytest.approx(fit.margin)
    proven = [proven_min_eig(Q) for Q in exact_lmis(fit.C, fit.M, g)]
    eigs = [np.linalg.eigvalsh(-lmi(F, fit.M, g))[0] for F in companion(fit.C)]
    assert all(p is not None and 0 < p <= e * (1 + 1e-6) for p, e in zip(proven, eigs))

"""Objectives: affine scalars and convex quadratics (sosdyn.sos.objective)."""
import numpy as np
import pytest

import sosdyn as sd


def test_least_squares_objective_and_linear_constraints():
    prog = sd.SOSProgram()
    u = prog.new_var(3)
    target = np.array([1.0, -2.0, 0.5])
    prog.minimize(sd.sum_squares([u[i, 0] - target[i] for i in range(3)]))
    prog.add_ge(u[1, 0], -1.0)
    prog.add_eq(u[2, 0], 0.0)
    sol = prog.solve()
    np.testing.assert_allclose(sol.value(u).ravel(), [1.0, -1.0, 0.0], atol=1e-6)
    assert sol.objective == pytest.approx(1.0 + 0.25, abs=1e-6)

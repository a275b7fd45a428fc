"""Explicit Euler with the rest stop rule, against its closed form."""

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError
from sosdyn.lfd.rollout import euler_until_rest


def test_euler_on_xdot_minus_x_is_the_geometric_sequence_and_stops_at_rest():
    dt, tol, window = 0.1, 0.05, 3
    reps = euler_until_rest(lambda X: -X, [[1.0, -2.0]], dt=dt, max_steps=1000, vel_tol=tol, window=window)
    x = reps[0]
    i = np.arange(len(x))
    np.testing.assert_allclose(x, np.outer(0.9 ** i, [1.0, -2.0]), rtol=1e-12)
    # |v_i| = 2 * 0.9^(i-1) < tol first at i = 37 (1-based); quiet for window steps: stop at i = 39
    first_quiet = int(np.ceil(np.log(tol / 2) / np.log(0.9))) + 1
    assert len(x) == first_quiet + window - 1


def test_euler_arguments_are_keywords_and_checked():
    with pytest.raises(TypeError):
        euler_until_rest(lambda X: -X, [[1.0]], 0.1, 10, 0.1, 2)
    with pytest.raises(InputError, match="window"):
        euler_until_rest(lambda X: -X, [[1.0]], dt=0.1, max_steps=10, vel_tol=0.1, window=0)
    with pytest.raises(SolverError, match="diverged"), np.errstate(over="ignore"):
        euler_until_rest(lambda X: X ** 2, [[10.0]], dt=0.5, max_steps=100, vel_tol=0.1, window=2)

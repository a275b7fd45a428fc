"""Explicit Euler with the rest stop rule, against its closed form."""

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError
from sosdyn.lfd.rollout import euler_arrival_times, euler_blocks_until_rest, euler_until_rest


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


def test_blocks_stop_on_their_own_and_a_diverging_block_leaves_the_others_alone():
    """Block 0: xdot = -x (rests at step 39 as above); block 1: xdot = -x/2 (slower); block 2:
    xdot = x^2 from 10 (blows up). Each block's trajectories equal euler_until_rest on its own."""
    rates = {0: -1.0, 1: -0.5}
    calls = []

    def field(X, live):
        calls.append(list(live))
        return np.vstack([X[k:k + 1] ** 2 if b == 2 else rates[b] * X[k:k + 1] for k, b in enumerate(live)])

    kw = dict(dt=0.1, max_steps=1000, vel_tol=0.05, window=3)
    with np.errstate(over="ignore"):
        out = euler_blocks_until_rest(field, [[1.0, -2.0], [1.0, -2.0], [10.0, 10.0]], 3, **kw)
    for b in (0, 1):
        alone = euler_until_rest(lambda X, r=rates[b]: r * X, [[1.0, -2.0]], **kw)
        assert len(out[b]) == 1 and np.array_equal(out[b][0], alone[0])
    assert len(out[0][0]) == 39 and len(out[1][0]) > 39
    assert isinstance(out[2], SolverError) and "diverged" in str(out[2])
    assert calls[0] == [0, 1, 2] and calls[-1] == [1]         # stopped blocks are no longer evaluated
    with pytest.raises(InputError, match="equal blocks"):
        euler_blocks_until_rest(field, [[1.0], [2.0], [3.0]], 2, **kw)


def test_arrival_times_are_the_geometric_sequence_s_first_entry_and_stop_each_start_on_its_own():
    """xdot = -a x: |x_i| = (1 - a dt)^i |x_0|, first within r at i = ceil(log(r / |x_0|) / log(1 - a dt)).
    Starts whose deadline comes before that, or whose state blows up, never arrive (inf); the field
    sees only the starts still running."""
    dt, r, a = 0.01, 0.05, np.array([1.0, 2.0, 1.0, 1.0])
    starts = np.array([[3.0, 4.0], [0.0, -2.0], [1.0, 0.0], [0.0, 0.01]])
    seen = []

    def field(X, rows):
        seen.append(rows.copy())
        return -a[rows, None] * X

    deadlines = np.array([100.0, 100.0, 0.5, 100.0])
    times = euler_arrival_times(field, starts, np.zeros(2), r, deadlines, dt=dt)
    first = np.ceil(np.log(r / np.linalg.norm(starts, axis=1)[:3]) / np.log(1 - a[:3] * dt))
    np.testing.assert_allclose(times[:2], first[:2] * dt, rtol=1e-12)
    assert first[2] * dt > deadlines[2] and times[2] == np.inf
    assert times[3] == 0.0                                   # starts inside: arrived at t = 0
    assert all(np.all(np.diff(s) > 0) for s in seen) and seen[0].tolist() == [0, 1, 2]
    assert len(seen) == first[0] and all(len(s) < 3 for s in seen[int(first[1]):])
    with np.errstate(over="ignore"):
        blown = euler_arrival_times(lambda X, rows: X ** 2, [[10.0]], np.zeros(1), 0.1, 100.0, dt=0.5)
    assert blown[0] == np.inf
    with pytest.raises(InputError, match="radius"):
        euler_arrival_times(field, starts, np.zeros(2), 0.0, deadlines, dt=dt)


def test_semi_implicit_euler_keeps_an_oscillator_bounded():
    from sosdyn.lfd.rollout import semi_implicit_euler
    X = semi_implicit_euler(lambda X, V: -X, [[1.0]], [[0.0]], dt=0.1, steps=1000)
    assert X.shape == (1001, 1, 1) and X[0, 0, 0] == 1.0
    assert 0.95 < np.abs(X[-200:, 0, 0]).max() < 1.06          # explicit Euler: amplitude x 1.005^1000 = 146
    with pytest.raises(SolverError):
        semi_implicit_euler(lambda X, V: X * 1e300, [[1.0]], [[0.0]], dt=1.0, steps=5)

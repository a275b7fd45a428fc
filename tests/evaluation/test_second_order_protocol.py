"""sosdyn.evaluation.second_order: the held-out protocol for first- and second-order fields, on known answers."""
import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.evaluation import dsopt
from sosdyn.evaluation.metrics import dtwd
from sosdyn.evaluation.second_order import evaluate, reproduce, semi_implicit_until_rest, start_states
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.rollout.euler import semi_implicit_euler

GOAL = np.array([1.0, -2.0])
K, D, DT = 4.0, 5.0, dsopt.DT          # xddot = -K (x - g) - D xdot: overdamped, rates 1 and 4


def accel(X, V):
    return -K * (X - GOAL) - D * V


def linear_demo(x0, steps=900) -> Demonstration:
    """Semi-implicit Euler of ``accel`` from (x0, 0) with dt = 0.01, written out here (not the
    harness's integrator): v_{k+1} = v_k + dt a(x_k, v_k), x_{k+1} = x_k + dt v_{k+1}."""
    x, v = np.array(x0, float), np.zeros(2)
    pos, vel = [x.copy()], [v.copy()]
    for _ in range(steps):
        v = v + DT * accel(x[None], v[None])[0]
        x = x + DT * v
        pos.append(x.copy())
        vel.append(v.copy())
    return Demonstration(DT * np.arange(steps + 1), np.array(pos), np.array(vel), "linear")


class Exact:
    """A "fitted" model: the system that generated the demos, certified by fiat."""

    goal_, certified_ = GOAL, True

    def __init__(self, train):
        self.train = train

    def predict(self, X, V):
        return accel(X, V)


def test_the_exact_system_reproduces_its_demo_from_the_20th_sample():
    demo = linear_demo(GOAL + [10.0, 5.0])               # from rest: a straight, monotone path to the goal
    test = Demonstrations([demo], "linear", "mm")
    (path,) = reproduce(accel, 2, test, test, "dsopt")
    s, L = dsopt.START_INDEX, dsopt.START_INDEX + len(path) - 1
    assert 100 < len(path) < 800                         # stopped at rest, well before the demo's end
    assert np.allclose(path, demo.pos[s:L + 1], rtol=0, atol=1e-10)
    # On a monotone straight path the optimal warping matches the unreproduced head to the first
    # point and the demo's tail to the last: DTWD = the sum of those distances, and ~0 without them.
    head = np.linalg.norm(demo.pos[:s] - demo.pos[s], axis=1).sum()
    tail = np.linalg.norm(demo.pos[L + 1:] - demo.pos[L], axis=1).sum()
    assert dtwd(path, demo.pos).total == pytest.approx(head + tail, rel=1e-9)
    assert dtwd(path, demo.pos[s:L + 1]).total < 1e-9


def test_evaluate_scores_against_copy_and_reads_the_certificate():
    starts = GOAL + np.array([[10, 5], [9, 6], [11, 4], [10, 7], [8, 5], [12, 6], [10, 3.0]])
    demos = Demonstrations([linear_demo(x) for x in starts], "linear", "mm")
    r = evaluate(Exact, demos, 2, "dsopt")
    assert r["n_train"] == 4 and r["n_test"] == 3 and r["certified"] is True and r["failure"] is None
    assert r["copy_mean"] > 0 and r["ratio"] == pytest.approx(r["dtwd_mean"] / r["copy_mean"])
    train, test = dsopt.split(demos)
    assert r["copy_mean"] == pytest.approx(dsopt.nearest_demo_score(train, test))
    assert r["arrival_ratio"] < 1 and r["excursion"] == 0 and r["final_error"] < 0.01
    same = evaluate(Exact, Demonstrations([demos[i] for i in (4, 5, 6, 0, 4, 5, 6)], "x", "mm"), 2, "dsopt")
    assert all(t["copy"] == 0.0 for t in same["tests"])   # each test demo is also a training demo


def test_first_order_equals_the_dsopt_protocol():
    starts = GOAL + np.array([[10, 5], [9, 6], [11, 4], [10, 7], [8, 5], [12, 6], [10, 3.0]])
    demos = Demonstrations([linear_demo(x) for x in starts], "linear", "mm")

    class Velocity(Exact):
        def predict(self, X):
            return -1.5 * (X - GOAL)

    ours, theirs = evaluate(Velocity, demos, 1, "dsopt"), dsopt.evaluate_shape(Velocity, demos)
    assert [t["dtwd"] for t in ours["tests"]] == pytest.approx(theirs["dtwd_test"], rel=1e-12)
    assert ours["copy_mean"] == pytest.approx(theirs["nearest_demo"])


def test_start_velocity_is_the_recorded_or_the_smoothed_one():
    t = 0.01 * np.arange(60)
    pos = np.column_stack([t**2, 3 * t**3])               # cubic: Savitzky-Golay (cubic) is exact
    noisy = Demonstration(t, pos, np.zeros_like(pos), "cubic")
    X0, V0 = start_states([noisy])
    assert np.array_equal(X0[0], pos[19]) and np.array_equal(V0[0], [0, 0])
    _, V0 = start_states([noisy], window=9)
    assert np.allclose(V0[0], [2 * t[19], 9 * t[19]**2], atol=1e-9)


def test_bad_inputs_and_divergence():
    demo = linear_demo(GOAL + [10.0, 5.0], steps=100)
    test = Demonstrations([demo], "linear", "mm")
    with pytest.raises(InputError, match="order"):
        reproduce(accel, 3, test, test, "dsopt")
    with pytest.raises(InputError, match="same shape"):
        semi_implicit_until_rest(accel, np.zeros((2, 2)), np.zeros((1, 2)), dt=0.01, max_steps=10, vel_tol=0.1, window=4)
    with pytest.raises(InputError, match="returned shape"):
        reproduce(lambda X, V: X[:, :1], 2, test, test, "dsopt")
    starts = GOAL + np.array([[10, 5], [9, 6], [11, 4], [10, 7], [8, 5], [12, 6], [10, 3.0]])
    demos = Demonstrations([linear_demo(x, steps=100) for x in starts], "linear", "mm")
    with pytest.raises(InputError, match="data_path"):
        evaluate(Exact, demos, 2, "lasa")

    class Unstable(Exact):
        def predict(self, X, V):
            with np.errstate(over="ignore", invalid="ignore"):
                return 1e3 * np.exp(np.minimum(np.abs(X), 700)) * X

    r = evaluate(Unstable, demos, 2, "dsopt")
    assert "diverged" in r["failure"] and "tests" not in r


def test_the_stopped_rollout_is_the_fixed_step_one_cut_at_rest():
    X0, V0 = GOAL + np.array([[10.0, 5.0], [-3.0, 8.0]]), np.array([[0.0, 0.0], [20.0, -5.0]])
    paths = semi_implicit_until_rest(accel, X0, V0, dt=DT, max_steps=3000, vel_tol=0.1, window=4)
    fixed = semi_implicit_euler(accel, X0, V0, dt=DT, steps=len(paths[0]) - 1)
    for k in range(2):
        assert np.allclose(paths[k], fixed[:, k], rtol=0, atol=1e-12)
    # stopped at rest: |v|, |a| < 0.1 per component, so |x - g| = |a + D v| / K < (0.1 + 0.5) / 4
    assert np.all(np.abs(paths[0][-1] - GOAL) < 0.15) and np.all(np.abs(paths[1][-1] - GOAL) < 0.15)

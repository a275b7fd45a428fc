"""The LPV-DS (ds-opt) LASA protocol: Euler stop rule, split, copy baseline, one shape."""

import math

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError, SosdynError
from sosdyn.evaluation.dsopt import (
    SINGLE_PATTERN_SHAPES,
    euler_reproduce,
    evaluate_shape,
    load_seds_published,
    nearest_demo_score,
    reproduction_scores,
    select_fit,
    split,
    start_points,
)
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.lasa import lasa_names, load_lasa


# ---------------------------------------------------------------- Euler reproduction


def test_euler_stop_rule_on_xdot_minus_x():
    """x_j = x_1 (1 - dt)^(j-1); v_j = -x_j is quiet once 30 (1 - dt)^(j-1) < 0.1 (30 = the largest
    component over both starts); stop 3 steps after the first quiet step, window 4."""
    starts = np.array([[30.0, -5.0], [2.0, 1.0]])
    dt = 0.01
    r = math.log(0.1 / 30.0) / math.log(1 - dt)        # quiet iff j - 1 > r
    assert abs(r - round(r)) > 1e-3                    # no tie at the threshold
    first_quiet = math.floor(r) + 2
    reps = euler_reproduce(lambda X: -X, starts, dt=dt)
    assert len(reps) == 2 and [len(x) for x in reps] == [first_quiet + 3] * 2 == [572, 572]
    j = np.arange(len(reps[0]))[:, None]
    for x, x1 in zip(reps, starts):
        np.testing.assert_allclose(x, x1 * (1 - dt) ** j, rtol=1e-12)
    np.testing.assert_array_less(np.abs(reps[0][-4:]), 0.1)          # the last 4 velocities |v| = |x|
    assert np.abs(reps[0][-5]).max() >= 0.1


def scripted_field(speeds):
    """Velocity (speed_k, 0) for every start at the k-th call, then 0."""
    calls = []

    def field(X):
        k = len(calls)
        calls.append(X.copy())
        return np.tile([speeds[k] if k < len(speeds) else 0.0, 0.0], (len(X), 1))

    return field


def test_euler_needs_window_consecutive_quiet_steps():
    # quiet (|v| < 0.1) at steps 2-4 and 6-9 (1-based): stop at step 9
    reps = euler_reproduce(scripted_field([1.0, 0.0, 0.0, 0.0, 1.0]), [[0.0, 0.0]], dt=0.5)
    assert len(reps[0]) == 9
    np.testing.assert_allclose(reps[0][:, 0], [0, 0.5, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0])


def test_euler_needs_every_start_quiet():
    field = lambda X: np.column_stack([0 * X[:, 0], np.where(X[:, 0] > 0, 1.0, 0.0)])  # noqa: E731
    reps = euler_reproduce(field, [[0.0, 0.0], [1.0, 0.0]], max_steps=50)
    assert [len(x) for x in reps] == [49, 49]


def test_euler_stops_at_max_steps_minus_one_and_tolerance_is_strict():
    # |v| = 0.1 exactly is not below vel_tol = 0.1: runs to the cap, x_j = x_1 + (j - 1) dt v
    reps = euler_reproduce(lambda X: np.full_like(X, 0.1), [[1.0, 2.0]], dt=0.01, max_steps=50)
    assert len(reps[0]) == 49
    np.testing.assert_allclose(reps[0][-1], [1.0 + 48 * 0.001, 2.0 + 48 * 0.001], rtol=1e-12)


def test_euler_zero_field_returns_window_points():
    reps = euler_reproduce(lambda X: np.zeros_like(X), [[1.0, 2.0]])
    np.testing.assert_array_equal(reps[0], [[1.0, 2.0]] * 4)


@pytest.mark.filterwarnings("ignore:overflow")
def test_euler_reports_divergence_and_bad_fields():
    with pytest.raises(SolverError, match="start 1 diverged"):
        euler_reproduce(lambda X: X**3, [[0.0, 0.0], [10.0, 0.0]], dt=0.1)
    with pytest.raises(InputError, match="shape"):
        euler_reproduce(lambda X: X[:, :1], [[1.0, 2.0]])
    with pytest.raises(InputError, match="max_steps"):
        euler_reproduce(lambda X: -X, [[1.0, 2.0]], max_steps=0)


# ---------------------------------------------------------------- split and starts


def tagged_demos(T):
    """7 demos; demo d has pos[k] = (d, k), vel[k] = (10 d, k), t = 0.1 k."""
    k = np.arange(T, dtype=float)
    return Demonstrations([Demonstration(0.1 * k, np.column_stack([0 * k + d, k]),
                                         np.column_stack([0 * k + 10 * d, k]), f"#{d}")
                           for d in range(7)], "tagged", "mm")


@pytest.mark.parametrize("T, kept", [(1000, 500), (41, 21)])
def test_split_keeps_demos_1_to_4_and_5_to_7_every_second_sample(T, kept):
    train, test = split(tagged_demos(T))
    assert [d.source for d in train] == ["#0", "#1", "#2", "#3"]
    assert [d.source for d in test] == ["#4", "#5", "#6"]
    assert train.name == "tagged" and test.units == "mm"
    for d in (*train, *test):
        tag = d.pos[0, 0]
        assert d.pos.shape == d.vel.shape == (kept, 2) and d.t.shape == (kept,)
        np.testing.assert_array_equal(d.pos[:, 1], np.arange(0, T, 2))    # samples 0, 2, 4, ...
        np.testing.assert_array_equal(d.vel, np.column_stack([0 * d.t + 10 * tag, np.arange(0, T, 2)]))
        np.testing.assert_allclose(d.t, 0.1 * np.arange(0, T, 2))
    np.testing.assert_array_equal(start_points(test), [[4, 38], [5, 38], [6, 38]])   # 20th kept


def test_split_needs_seven_demos():
    with pytest.raises(InputError, match="needs 7 demonstrations"):
        split(tagged_demos(30)[:6])


# ---------------------------------------------------------------- copy baseline and one shape


def test_nearest_demo_score_on_parallel_lines():
    x = np.linspace(0.0, 1.0, 50)
    line = lambda y: np.column_stack([x, 0 * x + y])  # noqa: E731
    # test y=1 is nearest to train y=0 (50 x 1), test y=18 to train y=20 (50 x 2)
    assert nearest_demo_score([line(0), line(5), line(20)], [line(1), line(18)]) == pytest.approx(75.0)


def test_evaluate_shape_with_a_zero_field_scores_distances_to_the_start():
    """xdot = 0 stops after 4 copies of the start p = pos[19]; the best path then pairs every demo
    point once with p, so DTWD = sum_k ||pos[k] - p||."""
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 1.0, 60)
    walks = [np.cumsum(rng.standard_normal((60, 2)), 0) for _ in range(7)]
    demos = Demonstrations([Demonstration(t, w, np.gradient(w, t, axis=0)) for w in walks], "walk", "mm")
    seen = []
    result = evaluate_shape(lambda train: seen.append(train) or (lambda X: np.zeros_like(X)), demos)
    assert len(seen[0]) == 4 and len(seen[0][0].t) == 30
    _, test = split(demos)
    expected = [np.linalg.norm(d.pos - d.pos[19], axis=1).sum() for d in test]
    assert result["dtwd_test"] == pytest.approx(expected, rel=1e-12)
    assert result["dtwd_test_mean"] == pytest.approx(np.mean(expected), rel=1e-12)
    assert result["n_points_test"] == result["n_points_train"] == 4 and result["failure"] is None
    assert result["nearest_demo"] == pytest.approx(nearest_demo_score(*split(demos)))


@pytest.mark.filterwarnings("ignore:overflow")
def test_evaluate_shape_scores_a_diverging_field_inf():
    demos = tagged_demos(60)
    result = evaluate_shape(lambda train: (lambda X: X**3 + 1.0), demos)
    assert result["dtwd_test_mean"] == np.inf and "diverged" in result["failure"]


# ---------------------------------------------------------------- shapes and published numbers


def test_single_pattern_shapes_are_lasa_without_multi_models():
    try:
        names = lasa_names()
    except SosdynError as exc:
        pytest.skip(f"LASA data unavailable: {exc}")
    assert len(SINGLE_PATTERN_SHAPES) == 26
    assert set(names) - set(SINGLE_PATTERN_SHAPES) == {f"Multi_Models_{k}" for k in range(1, 5)}
    train, test = split(load_lasa("Angle"))
    assert [len(d.t) for d in (*train, *test)] == [500] * 7


def test_load_seds_published(tmp_path):
    path = tmp_path / "seds.csv"
    path.write_text("shape,K_mean,dtwd_test_mean\nAngle,5.0,1171.5\nLine,3,243.9\n")
    assert load_seds_published(path) == {"Angle": {"K_mean": 5.0, "dtwd_test_mean": 1171.5},
                                         "Line": {"K_mean": 3.0, "dtwd_test_mean": 243.9}}
    path.write_text("name,dtwd\nAngle,1\n")
    with pytest.raises(InputError, match="no 'shape' column"):
        load_seds_published(path)
    with pytest.raises(InputError, match="Cannot read"):
        load_seds_published(tmp_path / "missing.csv")


# ---------------------------------------------------------------- selection on training demos


def _decaying_lines(starts, T=400, dt=0.01):
    """Demonstrations x(t) = x0 exp(-t): exactly the flow of xdot = -x."""
    t = np.arange(T) * dt
    return Demonstrations([Demonstration(t, np.outer(np.exp(-t), x0), -np.outer(np.exp(-t), x0), f"d{i}")
                           for i, x0 in enumerate(starts)], "lines", "mm")


def test_select_fit_sees_only_the_training_demos_and_picks_the_closer_field():
    demos = _decaying_lines([(300, 20), (250, -40), (280, 60), (320, 0), (0, 300), (-200, 100), (10, 10)])
    train, test = split(demos)
    seen = []

    def candidate(field):
        def fit(data):
            seen.append(data)
            return field
        return fit
    rotate = np.array([[0.0, 1.0], [-1.0, 0.0]])
    name, model, scores = select_fit({"spiral": candidate(lambda X: -X + X @ rotate.T),
                                      "exact": candidate(lambda X: -X)}, train)
    # By construction the candidates only ever get the training demonstrations (1-4).
    assert len(seen) == 2 and all(d is train for d in seen) and len(train) == 4
    assert name == "exact" and scores["exact"] < 0.2 * scores["spiral"]
    assert scores["exact"] == pytest.approx(np.mean(reproduction_scores(model, train)[0]))
    with pytest.raises(InputError, match="at least one candidate"):
        select_fit({}, train)

"""Accuracy metrics against known answers."""

import time

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.metrics import (
    dtwd,
    dtwd_reference,
    edot,
    evaluate_reproductions,
    goal_error,
    final_states,
    grid_convergence,
    grid_convergence_batched,
    grid_starts,
    quadrilateral_areas,
    sea,
    velocity_rmse,
)
from sosdyn.lfd.data import Demonstrations
from sosdyn.lfd.rollout import Trajectory, rollout


def curve(T, seed, n=2):
    return np.cumsum(np.random.default_rng(seed).standard_normal((T, n)), axis=0)


# ---------------------------------------------------------------- DTWD


def test_dtwd_of_identical_curves_is_zero():
    a = curve(200, 0)
    d = dtwd(a, a)
    assert d.total == 0 and d.per_point == 0 and d.n_points == (200, 200) and d.path_length == 200


@pytest.mark.parametrize("offset", [0.5, 3.0])
def test_dtwd_of_a_translate_is_n_times_the_offset(offset):
    s = np.linspace(0, 10, 300)
    line = np.column_stack([s, 0 * s])
    d = dtwd(line, line + [0, offset])
    assert d.total == pytest.approx(300 * offset) and d.per_point == pytest.approx(offset)
    lifted = np.column_stack([curve(150, 1), np.zeros(150)])  # a 2-D curve moved out of its plane
    d3 = dtwd(lifted, lifted + [0, 0, offset])
    assert d3.total == pytest.approx(150 * offset) and d3.per_point == pytest.approx(offset)


@pytest.mark.parametrize("seed, n", [(0, 1), (1, 2), (2, 2), (3, 3)])
def test_c_path_agrees_with_the_reference(seed, n):
    a, b = curve(60, seed, n), curve(45, seed + 100, n)
    fast, ref = dtwd(a, b), dtwd_reference(a, b)
    assert fast.total == pytest.approx(ref.total, rel=1e-12)
    assert fast.path_length == ref.path_length and fast.per_point == pytest.approx(ref.per_point, rel=1e-12)
    assert dtwd(b, a).total == pytest.approx(fast.total, rel=1e-12)


def test_dtwd_is_cumulative_euclidean_not_root_of_squares():
    a, b = np.zeros((2, 2)), np.array([[3.0, 4.0], [3.0, 4.0]])
    assert dtwd(a, b).total == pytest.approx(10.0)  # 5 + 5, not sqrt(25 + 25)


def test_dtwd_is_fast_on_1000_points():
    a, b = curve(1000, 5), curve(1000, 6)
    dtwd(a, b)
    start = time.perf_counter()
    dtwd(a, b)
    assert time.perf_counter() - start < 0.5


def test_dtwd_accepts_trajectories_and_demos(exp_demos, exp_goal):
    demo = exp_demos[0]
    traj = Trajectory(demo.t, demo.pos.copy(), np.tile(exp_goal, (len(demo.t), 1)))
    assert dtwd(traj, demo).total == 0


def test_dtwd_bad_inputs():
    with pytest.raises(InputError, match="dimensions 2 and 3"):
        dtwd(curve(10, 0), curve(10, 0, 3))
    with pytest.raises(InputError, match="NaN"):
        dtwd(np.array([[0.0, np.nan]]), curve(10, 0))
    with pytest.raises(InputError, match="shape"):
        dtwd(np.arange(5.0), curve(10, 0))
    with pytest.raises(InputError, match="shape"):
        dtwd(np.zeros((0, 2)), curve(10, 0))


# ---------------------------------------------------------------- SEA


def test_sea_of_parallel_segments_is_the_rectangle():
    s = np.linspace(0, 4, 51)
    demo = np.column_stack([s, 0 * s])
    assert sea(demo + [0, 1.5], demo) == pytest.approx(6.0)
    assert sea(demo, demo) == 0
    fine = np.linspace(0, 4, 201)  # a finer reproduction over the same time span is resampled
    reproduction = Trajectory(fine * 2.5, np.column_stack([fine, 1.5 + 0 * fine]), np.zeros((201, 2)))
    assert sea(reproduction, demo) == pytest.approx(6.0)


def test_sea_of_a_bow_tie_adds_the_two_triangles():
    # quadrilateral (0,0) -> (2,2) -> (2,0) -> (0,2): edges cross at (1,1), two triangles of area 1
    assert sea(np.array([[0.0, 0], [2, 2]]), np.array([[0.0, 2], [2, 0]])) == pytest.approx(2.0)
    quad = [np.array([p], float) for p in [(0, 0), (0, 2), (2, 0), (2, 2)]]  # other pair of edges crosses
    assert quadrilateral_areas(*quad)[0] == pytest.approx(2.0)
    skewed = [np.array([p], float) for p in [(0, 0), (3, 3), (3, 0), (0, 1)]]  # cross at (0.75, 0.75)
    assert quadrilateral_areas(*skewed)[0] == pytest.approx(0.5 * 0.75 + 0.5 * 3 * 2.25)


def test_quadrilateral_areas_non_convex_and_higher_dimensions():
    arrow = [(0, 0), (4, 0), (4, 4), (3, 1)]  # simple, non-convex: 8 - 4
    assert quadrilateral_areas(*[np.array([p], float) for p in arrow])[0] == pytest.approx(4.0)
    in_3d = [np.array([[*p, 0.0]]) for p in arrow]
    assert quadrilateral_areas(*in_3d)[0] == pytest.approx(4.0)
    rotation, _ = np.linalg.qr(np.random.default_rng(0).standard_normal((4, 4)))
    s = np.linspace(0, 4, 51)
    demo = np.column_stack([s, 0 * s, 0 * s, 0 * s]) @ rotation.T
    shifted = np.column_stack([s, 1.5 + 0 * s, 0 * s, 0 * s]) @ rotation.T
    assert sea(shifted, demo) == pytest.approx(6.0)


def test_sea_penalises_timing():
    angle = np.linspace(0, np.pi, 100)
    demo = np.column_stack([np.cos(angle), np.sin(angle)])
    late = np.column_stack([np.cos(angle**2 / np.pi), np.sin(angle**2 / np.pi)])  # same path, other timing
    assert sea(late, demo) > 0.1 and dtwd(late, demo).per_point < 0.02


def test_sea_bad_inputs():
    with pytest.raises(InputError, match="dimension"):
        sea(curve(10, 0, 3), curve(10, 0))
    with pytest.raises(InputError, match=">= 2 samples"):
        sea(curve(1, 0), curve(10, 0))


# ---------------------------------------------------------------- velocity errors


def test_velocity_errors_of_exact_scaled_and_reversed_models(exp_model, exp_demos, exp_goal):
    assert velocity_rmse(exp_model, exp_demos) == pytest.approx(0, abs=1e-12)
    assert edot(exp_model, exp_demos) == pytest.approx(0, abs=1e-12)
    X, _ = exp_demos.stacked()
    twice = lambda X: -2 * (X - exp_goal)  # noqa: E731
    rms_distance = np.sqrt(np.mean(np.sum((X - exp_goal) ** 2, axis=1)))
    assert velocity_rmse(twice, exp_demos) == pytest.approx(rms_distance)
    assert edot(twice, exp_demos) == pytest.approx(0, abs=1e-12)
    assert edot(lambda X: X - exp_goal, exp_demos) == pytest.approx(2.0)
    assert velocity_rmse(exp_model, exp_demos[0]) == pytest.approx(0, abs=1e-12)


def test_velocity_error_bad_inputs(exp_model, exp_demos):
    with pytest.raises(InputError, match="predict returned shape"):
        velocity_rmse(lambda X: X[:, :1], exp_demos)
    with pytest.raises(InputError, match="NaN"):
        edot(lambda X: X * np.nan, exp_demos)
    with pytest.raises(InputError, match="min_speed"):
        edot(exp_model, exp_demos, min_speed=1e6)
    with pytest.raises(InputError, match=r"\.predict"):
        velocity_rmse(42, exp_demos)
    with pytest.raises(InputError, match="non-empty"):
        velocity_rmse(exp_model, Demonstrations([]))


def test_goal_error():
    traj = Trajectory(np.arange(2.0), np.array([[0.0, 0.0], [4.0, 1.0]]), np.zeros((2, 2)))
    assert goal_error(traj, [1.0, 5.0]) == pytest.approx(5.0)
    with pytest.raises(InputError, match="goal has shape"):
        goal_error(traj, [1.0])


# ---------------------------------------------------------------- grid convergence


def test_stable_model_converges_from_the_whole_grid(exp_model, exp_demos):
    result = grid_convergence(exp_model, exp_demos, n_grid=10)
    assert result.fraction == 1.0 and result.n_starts == 100 and result.failures == []


def test_half_plane_model_converges_from_half_the_grid(exp_demos, exp_goal):
    centre = 2.0  # x range of the data is [-5, 9]
    field = lambda X, g: -(X - g) * (X[:, :1] < centre)  # noqa: E731

    def roll(x0, duration, dt):
        return rollout(field, x0, duration=duration, dt=dt, goal=exp_goal)

    result = grid_convergence(roll, exp_demos, n_grid=10, horizon=20.0)
    assert result.fraction == 0.5 and len(result.failures) == 50
    assert all(f["x0"][0] > centre and f["final_error"] > 1.0 for f in result.failures)


def test_grid_counts_solver_failures(exp_demos):
    def broken(x0, duration, dt):
        raise SolverError("diverged")

    result = grid_convergence(broken, exp_demos, n_grid=3)
    assert result.fraction == 0 and result.failures[0]["final_error"] == np.inf
    assert "diverged" in result.failures[0]["reason"]


def test_batched_grid_agrees_with_the_per_start_loop(exp_model, exp_demos, exp_goal):
    batched = grid_convergence_batched(exp_model, exp_demos, n_grid=10)
    assert batched.fraction == 1.0 and batched.n_starts == 100 and batched.failures == []
    centre = 2.0
    field = lambda X, g: -(X - g) * (X[:, :1] < centre)  # noqa: E731

    def roll(x0, duration, dt):
        return rollout(field, x0, duration=duration, dt=dt, goal=exp_goal)

    loop = grid_convergence(roll, exp_demos, n_grid=6, horizon=20.0)
    half = grid_convergence_batched(field, exp_demos, n_grid=6, horizon=20.0, goal=exp_goal)
    assert half.fraction == loop.fraction == 0.5
    for a, b in zip(loop.failures, half.failures):
        np.testing.assert_array_equal(a["x0"], b["x0"])
        assert b["final_error"] == pytest.approx(a["final_error"], rel=1e-5)


def test_batched_final_states_match_the_exact_solution(exp_goal):
    starts = np.array([[9.0, 3.0], [-5.0, 4.0], [100.0, -50.0]])
    final, reasons = final_states(lambda X, g: -(X - g), starts, 3.0, exp_goal)
    np.testing.assert_allclose(final, exp_goal + (starts - exp_goal) * np.exp(-3.0), rtol=1e-5)
    assert reasons == [None, None, None]
    for method in ("BDF", "Radau"):
        other, _ = final_states(lambda X, g: -(X - g), starts, 3.0, exp_goal, method=method)
        np.testing.assert_allclose(other, final, rtol=1e-4)


def test_batched_grid_isolates_failing_starts(exp_demos, exp_goal):
    def field(X, g):  # NaN for starts left of x = 0: only those fail, found by bisection
        V = -(X - g)
        V[X[:, 0] < 0] = np.nan
        return V

    result = grid_convergence_batched(field, exp_demos, n_grid=4, goal=exp_goal, horizon=20.0)
    bad = [f for f in result.failures]
    assert len(bad) == 8 and all(f["x0"][0] < 0 and f["final_error"] == np.inf for f in bad)
    assert all("NaN" in f["reason"] for f in bad) and result.fraction == 0.5
    with pytest.raises(InputError, match="method"):
        final_states(field, np.zeros((1, 2)), 1.0, exp_goal, method="RK45")


def test_grid_starts_cover_twice_the_bounding_box(exp_demos, make_exp_demo):
    starts = grid_starts(exp_demos, n_grid=5)
    X, _ = exp_demos.stacked()
    lo, hi = X.min(axis=0), X.max(axis=0)
    np.testing.assert_allclose(starts.min(axis=0), 1.5 * lo - 0.5 * hi)
    np.testing.assert_allclose(starts.max(axis=0), 1.5 * hi - 0.5 * lo)
    assert starts.shape == (25, 2)
    d3 = Demonstrations([make_exp_demo([1.0, 2.0, 3.0], goal=np.zeros(3))])
    random_starts = grid_starts(d3, n_grid=4, seed=7)
    assert random_starts.shape == (16, 3)
    np.testing.assert_array_equal(random_starts, grid_starts(d3, n_grid=4, seed=7))
    with pytest.raises(InputError, match="n_grid"):
        grid_starts(exp_demos, n_grid=1)


# ---------------------------------------------------------------- reproductions


def test_exact_model_reproduces_its_demos(exp_model, exp_demos, exp_goal):
    result = evaluate_reproductions(exp_model, exp_demos)
    assert len(result["trajectories"]) == 3 and len(result["trajectories"][0].t) == 301
    assert max(result["sea"]) < 1e-6 and max(result["dtwd_per_point"]) < 1e-5  # solver tolerance
    expected = [np.linalg.norm(d.pos[0] - exp_goal) * np.exp(-6.0) for d in exp_demos]
    np.testing.assert_allclose(result["goal_error"], expected, rtol=1e-4)
    assert result["mean"]["goal_error"] == pytest.approx(np.mean(expected), rel=1e-4)
    assert set(result["std"]) == {"sea", "dtwd", "dtwd_per_point", "goal_error"}


def test_model_with_another_goal_has_positive_sea_and_dtwd(exp_demos, exp_goal, exp_model_cls):
    result = evaluate_reproductions(exp_model_cls(goal=exp_goal + [0.0, 2.0]), exp_demos)
    assert min(result["sea"]) > 1.0 and min(result["dtwd_per_point"]) > 0.5
    assert max(result["goal_error"]) < 0.05  # measured to the model's own goal

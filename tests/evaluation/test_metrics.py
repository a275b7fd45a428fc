"""Accuracy metrics against known answers."""

import numpy as np
import pytest

from sosdyn.errors import InputError, ResourceLimitError, SosdynError
from sosdyn.evaluation.metrics import dtwd, edot, goal_error, quadrilateral_areas, sea, velocity_rmse
from sosdyn.limits import limits
from sosdyn.lfd.data.demonstrations import Demonstrations
from sosdyn.lfd.rollout import Trajectory


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
def test_c_path_agrees_with_the_reference(seed, n, reference_dtw):
    a, b = curve(60, seed, n), curve(45, seed + 100, n)
    fast, ref = dtwd(a, b), reference_dtw(a, b)
    assert fast.total == pytest.approx(ref.total, rel=1e-12)
    assert fast.path_length == ref.path_length and fast.per_point == pytest.approx(ref.per_point, rel=1e-12)
    assert dtwd(b, a).total == pytest.approx(fast.total, rel=1e-12)


def test_dtwd_is_cumulative_euclidean_not_root_of_squares():
    a, b = np.zeros((2, 2)), np.array([[3.0, 4.0], [3.0, 4.0]])
    assert dtwd(a, b).total == pytest.approx(10.0)  # 5 + 5, not sqrt(25 + 25)


def test_dtwd_runs_the_c_routine_once_never_the_python_loop(monkeypatch, reference_dtw):
    """What makes DTW fast (its timings are benchmark targets: problems.bench.dtw, `make bench`): one
    call of dtaidistance's C routine per distance, never its pure-Python double loop."""
    from dtaidistance import dtw

    calls, c_routine = [], dtw.dtw_cc.warping_paths_ndim
    monkeypatch.setattr(dtw.dtw_cc, "warping_paths_ndim", lambda *a, **k: calls.append(1) or c_routine(*a, **k))
    monkeypatch.setattr(dtw, "warping_paths", lambda *a, **k: pytest.fail("the pure-Python DTW ran"))
    a, b = curve(300, 5), curve(200, 6)
    assert dtwd(a, b).total == pytest.approx(reference_dtw(a, b).total, rel=1e-12) and calls == [1]


def test_dtwd_without_the_c_extension_is_refused(monkeypatch):
    from dtaidistance import dtw

    monkeypatch.setattr(dtw, "try_import_c", lambda *a, **k: False)
    with pytest.raises(SosdynError, match="without its C extension.*pip install --force-reinstall"):
        dtwd(curve(10, 0), curve(10, 1))


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


def total(a, b):
    return dtwd(a, b).total


def test_dtw_hand_computed():
    # cost |a_i - b_j| = [[0, 2], [1, 1], [2, 0]]; best path (0,0) (1,0) (2,1) costs 0 + 1 + 0
    assert total([[0.0], [1.0], [2.0]], [[0.0], [2.0]]) == 1.0
    # one point against a curve: every point of the curve is paired with it once
    assert total([[0.0, 0.0]], [[3.0, 4.0], [0.0, 0.0], [6.0, 8.0]]) == 15.0
    assert total([[3.0, 4.0], [0.0, 0.0], [6.0, 8.0]], [[0.0, 0.0]]) == 15.0


def test_dtw_of_parallel_lines_is_n_times_offset():
    x = np.linspace(0.0, 10.0, 40)
    a, b = np.column_stack([x, 0 * x]), np.column_stack([x, 0 * x + 1.5])
    assert total(a, b) == pytest.approx(40 * 1.5, rel=1e-12)
    assert total(a, a) == 0.0


@pytest.mark.parametrize("N, M, n", [(1, 1, 2), (1, 7, 2), (9, 1, 3), (5, 8, 2), (13, 6, 1), (24, 31, 2)])
def test_dtw_matches_double_loop(N, M, n, reference_dtw):
    rng = np.random.default_rng(N * 100 + M)
    a, b = rng.standard_normal((N, n)) * 3, rng.standard_normal((M, n)) * 3
    expected = reference_dtw(a, b).total
    assert total(a, b) == pytest.approx(expected, rel=1e-12)
    assert total(b, a) == pytest.approx(expected, rel=1e-12)


def test_dtw_cost_matrix_is_checked_against_max_bytes():
    a = curve(1000, 0)
    with limits(max_bytes=8 * 1001 * 1001 - 1), pytest.raises(ResourceLimitError, match="DTW of 1000 x 1000"):
        dtwd(a, a)
    with limits(max_bytes=8 * 1001 * 1001):
        assert dtwd(a, a).total == 0.0


def test_dtw_rejects_bad_curves():
    with pytest.raises(InputError, match="dimensions 2 and 3"):
        total(np.zeros((4, 2)), np.zeros((4, 3)))
    with pytest.raises(InputError, match="NaN or inf"):
        total([[0.0, np.nan]], np.zeros((4, 2)))


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

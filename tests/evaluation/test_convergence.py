"""Grid convergence, per start and batched, and the call-budget policy on a grid."""

import numpy as np
import pytest

from sosdyn.errors import InputError, SolverError
from sosdyn.evaluation.convergence import (grid_convergence, grid_convergence_batched,
                                           grid_convergence_budget, grid_starts)
from sosdyn.lfd.data.demonstrations import Demonstrations
from sosdyn.lfd.rollout import rollout


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


def test_batched_grid_isolates_failing_starts(exp_demos, exp_goal):
    def field(X, g):  # NaN for starts left of x = 0: only those fail, found by bisection
        V = -(X - g)
        V[X[:, 0] < 0] = np.nan
        return V

    result = grid_convergence_batched(field, exp_demos, n_grid=4, goal=exp_goal, horizon=20.0)
    bad = [f for f in result.failures]
    assert len(bad) == 8 and all(f["x0"][0] < 0 and f["final_error"] == np.inf for f in bad)
    assert all("NaN" in f["reason"] for f in bad) and result.fraction == 0.5


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


def test_grid_under_the_budget_policy_falls_back_to_bdf_then_gives_up(exp_model, exp_demos):
    exp_model.goal_ = exp_model.goal
    result, integrator = grid_convergence_budget(exp_model, exp_demos, n_grid=3)
    assert integrator == "LSODA" and result.fraction == 1.0 and result.n_starts == 9
    # LSODA needs more than 5 calls on this grid; BDF gets 10**4
    result, integrator = grid_convergence_budget(exp_model, exp_demos, n_grid=3,
                                                 budgets=(("LSODA", 5), ("BDF", 10**4)))
    assert integrator == "BDF" and result.fraction == 1.0
    assert grid_convergence_budget(exp_model, exp_demos, n_grid=3,
                                   budgets=(("LSODA", 5), ("BDF", 5))) == (None, "budget exceeded")

"""The learning stages as functions on arrays: the same numbers as the estimator, the shared rules."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.fit.learner import (LEARNER_HINT, History, Settings, StepCache, active_step_cache, embed, learn,
                                reuse_steps, stalled, subsample, with_learner_hint)
from sosdyn.lfd.fit.steps import DynamicsStep, ICAStep, MetricStep


def test_learn_gives_the_estimators_numbers_and_history(linear_demos):
    model = sd.CDSP(n_components=1, gamma=0.5, metric_degree=2, max_iter=3, warp="none").fit(linear_demos)
    X, Xdot = linear_demos.stacked()
    Z, Zdot = (X - model.goal_) / model.scale_, Xdot / model.scale_
    rows = []
    history = History(progress=rows.append)
    C, W, mixture = learn(Z, Zdot, model.mixture_, Settings.from_params(model.get_params()), history)
    np.testing.assert_array_equal(C, model.C_)
    np.testing.assert_array_equal(W, model.W_)
    assert mixture is model.mixture_                                   # no refinement asked
    assert [r["step"] for r in history.rows] == [r["step"] for r in model.history_]
    assert history.rows[0]["step"] == "dynamics (M = I)" and history.rows[-1]["iteration"] == len(rows) - 1
    assert rows == history.rows


def test_fits_in_one_reuse_block_share_their_steps_and_give_the_fresh_numbers(linear_demos):
    """Two fits of one structure on different data: inside reuse_steps() the second compiles no
    step (ICA, both dynamics steps and the metric step are reused) and both give exactly the
    numbers of fresh steps."""
    model = sd.CDSP(n_components=2, metric_degree=2, max_iter=2, warp="none").fit(linear_demos)
    X, Xdot = linear_demos.stacked()
    Z, Zdot = (X - model.goal_) / model.scale_, Xdot / model.scale_
    s = Settings.from_params(model.get_params())
    data = [(Z, Zdot), (Z, 0.7 * Zdot + 0.05 * Z[:, ::-1])]
    fresh = [learn(z, zd, model.mixture_, s, History()) for z, zd in data]
    assert active_step_cache() is None
    with reuse_steps():
        cache = active_step_cache()
        first = learn(*data[0], model.mixture_, s, History())
        steps = dict(cache.steps)
        second = learn(*data[1], model.mixture_, s, History())
        assert cache.steps == steps and len(steps) == 4
        assert {key[0] for key in steps} == {DynamicsStep, ICAStep, MetricStep}
    assert active_step_cache() is None and isinstance(cache, StepCache)
    for got, want in zip((first, second), fresh):
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
    assert not np.allclose(first[0], second[0])


def test_settings_and_the_learned_metric_degree():
    s = Settings.from_params(sd.CDSP(metric_degree=2).get_params())
    assert s.learned_metric_degree == 2 and s.solver_method == "ica" and s.metric_prox == 0.01
    assert Settings.from_params(sd.CDSP(metric_degree=2, metric="identity").get_params()).learned_metric_degree == 0


def test_stopping_test_is_relative_with_a_floor():
    assert stalled(1.0, 1.0 - 1e-5, 1e-4) and not stalled(1.0, 0.9, 1e-4)
    assert stalled(0.0, 0.0, 1e-4) and not stalled(0.0, -1e-11, 1e-4)   # floor 1e-12


def test_subsample_takes_every_step_th_row():
    X = np.arange(20.0).reshape(10, 2)
    Xs, Vs, done = subsample(X, -X, 3)
    np.testing.assert_array_equal(Xs[:, 0], [0.0, 8.0, 16.0])
    np.testing.assert_array_equal(Vs, -Xs)
    assert done and subsample(X, X, None)[2] is False and subsample(X, X, 10)[0] is X


def test_embed_places_coefficients_at_their_monomials():
    small = np.array([[1, 0], [0, 1]])
    big = np.array([[0, 1], [2, 0], [1, 0], [1, 1]])
    np.testing.assert_array_equal(embed(np.array([[5.0, 7.0]]), small, big), [[7.0, 0.0, 5.0, 0.0]])


def test_solver_errors_get_the_learners_hint_first():
    exc = with_learner_hint(sd.InfeasibleError("program 'x' is infeasible.", "infeasible", "a higher degree"))
    assert type(exc) is sd.InfeasibleError and exc.status == "infeasible"
    assert str(exc) == f"CDSP fit failed: program 'x' is infeasible. Try: {LEARNER_HINT}; or a higher degree"
    report = object()
    unverified = with_learner_hint(sd.UnverifiedSolutionError("bad", hint=None, report=report))
    assert unverified.report is report and unverified.hint == LEARNER_HINT
    with pytest.raises(sd.SolverError, match="smaller gamma"):
        raise with_learner_hint(sd.SolverError("failed", "solver_error"))

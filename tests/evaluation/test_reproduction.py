"""Reproductions of the demonstrations and the mean/std summaries."""

import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.evaluation.reproduction import (describe, evaluate_reproductions, mean_std, rollout_to_goal,
                                            summarize)


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


def test_mean_std_describe_and_summarize_known_answers():
    assert mean_std([1.0, 2.0, 3.0, 6.0]) == (3.0, pytest.approx(np.sqrt(3.5)))   # ddof = 0
    assert mean_std([1.0, np.inf]) == (np.inf, np.inf) and mean_std([]) == (np.inf, np.inf)
    assert describe(np.array([2, 4])) == {"mean": 3.0, "std": 1.0, "per_demo": [2.0, 4.0]}
    means, stds = summarize({"a": [1.0, 3.0], "b": [0.0, np.nan]})
    assert means == {"a": 2.0, "b": np.inf} and stds == {"a": 1.0, "b": np.inf}


def test_rollout_to_goal_refuses_bad_durations(exp_model):
    for kwargs in ({"duration": 0.0}, {"duration": 5.0, "max_duration": 4.0}, {"duration": 1.0, "tol": 0.0}):
        args = {"duration": 1.0, "max_duration": 4.0, "tol": 1.0, **kwargs}
        with pytest.raises(InputError, match="duration"):
            rollout_to_goal(exp_model.rollout, [1.0, 1.0], args.pop("duration"), dt=0.1, **args)

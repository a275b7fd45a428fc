"""The call-budget policy (LSODA, then BDF) and budgeted rollouts of a model."""

import numpy as np
import pytest

from sosdyn.errors import InputError, NotFittedError, SolverError
from sosdyn.lfd.rollout import (BudgetExceeded, BudgetRollout, CountedField, rollout,
                                run_with_budget)

GOAL = np.array([1.0, -2.0])


class Linear:
    """A fitted model xdot = -(x - goal) with goal_ and dt_."""

    goal_, dt_ = GOAL, 0.05

    def field(self, X, goal):
        return -(X - goal)


def test_counted_field_raises_after_its_budget():
    counted = CountedField(lambda X, g: X, budget=2)
    counted(np.zeros((1, 1)), None), counted(np.zeros((1, 1)), None)
    assert counted.calls == 2
    with pytest.raises(BudgetExceeded, match="more than 2 field evaluations"):
        counted(np.zeros((1, 1)), None)
    assert not issubclass(BudgetExceeded, SolverError)   # batched integrators must not swallow it


def test_policy_tries_integrators_in_order_and_other_errors_propagate():
    used = []

    def run(field, integrator):
        used.append(integrator)
        for _ in range(10):
            field(None, None)
        return integrator

    counted_field = lambda X, g: 0.0  # noqa: E731
    assert run_with_budget(run, counted_field, (("LSODA", 5), ("BDF", 20))) == ("BDF", "BDF")
    assert used == ["LSODA", "BDF"]
    with pytest.raises(BudgetExceeded):
        run_with_budget(run, counted_field, (("LSODA", 5), ("BDF", 5)))

    def failing(field, integrator):
        raise SolverError("blew up")

    with pytest.raises(SolverError, match="blew up"):
        run_with_budget(failing, counted_field, (("LSODA", 5), ("BDF", 20)))


def test_budget_rollout_equals_the_plain_rollout_and_counts_fallbacks():
    roll = BudgetRollout(Linear())
    traj = roll([4.0, 3.0], 2.0)
    plain = rollout(Linear().field, [4.0, 3.0], duration=2.0, dt=0.05, goal=GOAL)
    np.testing.assert_array_equal(traj.pos, plain.pos)
    assert (roll.fallbacks, roll.failures) == (0, 0)
    tight = BudgetRollout(Linear(), budgets=(("LSODA", 10), ("BDF", 10**4)))
    bdf = tight([4.0, 3.0], 2.0, perturbations=[(1.0, [1.0, 0.0])])
    np.testing.assert_array_equal(bdf.pos, rollout(Linear().field, [4.0, 3.0], duration=2.0, dt=0.05, goal=GOAL,
                                                   perturbations=[(1.0, [1.0, 0.0])], integrator="BDF").pos)
    assert (tight.fallbacks, tight.failures) == (1, 0)
    hopeless = BudgetRollout(Linear(), budgets=(("LSODA", 10), ("BDF", 10)))
    with pytest.raises(SolverError, match="integration budget exceeded"):
        hopeless([4.0, 3.0], 2.0)
    assert (hopeless.fallbacks, hopeless.failures) == (1, 1)


@pytest.mark.parametrize("kwargs, error, message", [
    ({"dt": 0}, InputError, "dt must be a finite number > 0"),        # never replaced by dt_
    ({"duration": True}, InputError, "duration must be"),
    ({"x0": [1.0, 2.0, 3.0]}, InputError, r"x0 has shape \(3,\)"),
    ({"goal": [0.0]}, InputError, "goal has shape"),
    ({"perturbations": [(9.0, [1.0, 0.0])]}, InputError, "not inside"),
])
def test_budget_rollout_has_the_model_rollout_checks(kwargs, error, message):
    args = {"x0": [4.0, 3.0], "duration": 2.0} | kwargs
    with pytest.raises(error, match=message):
        BudgetRollout(Linear())(args.pop("x0"), args.pop("duration"), **args)


def test_budget_rollout_of_an_unfitted_model():
    class Unfitted:
        def field(self, X, goal):
            return X

    with pytest.raises(NotFittedError, match="not fitted"):
        BudgetRollout(Unfitted())([0.0], 1.0)

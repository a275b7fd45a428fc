"""The call-budget policy: LSODA first, BDF when LSODA exceeds its budget of field calls.

Fields with switched corrections (CLF-DM's correction turns on and off across the surface
grad V . f + rho = 0) make LSODA's stiff/non-stiff switching chatter (70 000 calls for one
BendedLine demonstration); BDF integrates them steadily. Every attempt uses the same
rtol/atol, so results agree to the tolerance. :func:`run_with_budget` is the policy for
any integration; :class:`BudgetRollout` applies it to a fitted model's rollouts.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from sosdyn.errors import NotFittedError, SolverError
from sosdyn.lfd.rollout.adaptive import rollout
from sosdyn.lfd.rollout.events import Field, Trajectory, as_vector

#: (integrator, field-call budget) tried in order, for one rollout and for a batched grid.
ROLLOUT_BUDGETS = (("LSODA", 6_000), ("BDF", 40_000))
GRID_BUDGETS = (("LSODA", 20_000), ("BDF", 100_000))


class BudgetExceeded(Exception):
    """An integration used more field calls than its budget.

    Deliberately not a SolverError: the batched integrators split a batch on SolverError,
    whereas an overrun must abort the whole attempt and move on to the next integrator.
    """


class CountedField:
    """``field`` with a budget: the call after ``budget`` calls raises :class:`BudgetExceeded`.

    The wrapped field is stored as ``wrapped``, not ``field``: callers that accept a model or
    a field take ``getattr(obj, "field", obj)``, which must return this counter itself.
    """

    def __init__(self, field: Field, budget: int):
        self.wrapped, self.budget, self.calls = field, budget, 0

    def __call__(self, X, goal):
        self.calls += 1
        if self.calls > self.budget:
            raise BudgetExceeded(f"more than {self.budget} field evaluations")
        return self.wrapped(X, goal)


def run_with_budget(run: Callable[[Field, str], object], field: Field,
                    budgets: Sequence[tuple[str, int]]) -> tuple[object, str]:
    """``(run(CountedField(field, budget), integrator), integrator)`` for the first
    ``(integrator, budget)`` of ``budgets`` whose run stays within its budget. Other errors
    propagate at once; if every run overruns, the last :class:`BudgetExceeded` is raised."""
    for integrator, budget in budgets:
        try:
            return run(CountedField(field, budget), integrator), integrator
        except BudgetExceeded as exc:
            last = exc
    raise last


class BudgetRollout:
    """``model.rollout`` under the budget policy: ``BudgetRollout(model)(x0, duration, ...)``.

    ``model`` is fitted and has ``field(X, goal)``, ``goal_`` and ``dt_`` (CDSP, GMR, CLF-DM).
    The arguments get the checks of ``model.rollout``: fitted, ``x0`` a finite vector of the
    model's dimension, ``dt=None`` / ``goal=None`` mean the model's ``dt_`` / ``goal_`` (never
    replaced otherwise), and everything else is checked by :func:`rollout`. Counts
    ``fallbacks`` (runs that left an integrator for the next) and ``failures`` (runs over
    every budget, raised as SolverError, which the metrics count as failed rollouts).
    """

    def __init__(self, model, budgets: Sequence[tuple[str, int]] = ROLLOUT_BUDGETS):
        self.model, self.budgets = model, tuple(budgets)
        self.fallbacks = 0
        self.failures = 0

    def __call__(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()) -> Trajectory:
        model = self.model
        if not hasattr(model, "goal_"):
            raise NotFittedError(f"This {type(model).__name__} model is not fitted yet; call fit(demos) first.")
        x0 = as_vector(x0, len(model.goal_), "x0")
        goal = model.goal_ if goal is None else goal
        dt = model.dt_ if dt is None else dt

        def run(field, integrator):
            return rollout(field, x0, duration=duration, dt=dt, goal=goal, perturbations=perturbations,
                           goal_changes=goal_changes, scale=getattr(model, "scale_", None), integrator=integrator)

        try:
            traj, integrator = run_with_budget(run, model.field, self.budgets)
        except BudgetExceeded as exc:
            self.fallbacks += len(self.budgets) - 1
            self.failures += 1
            raise SolverError(f"integration budget exceeded: {exc}", status="solver_error") from None
        self.fallbacks += [name for name, _ in self.budgets].index(integrator)
        return traj

"""Every integrator of sosdyn, in one place.

* :func:`rollout`: one trajectory of ``xdot = field(x, goal)`` with pushes and goal changes
  (adaptive, LSODA by default; used by ``CDSP.rollout`` and the baselines);
* :func:`final_states`: ``x(horizon)`` from many starts as one batched ODE (grid convergence);
* :func:`run_with_budget` / :class:`BudgetRollout`: the call-budget policy, LSODA then BDF;
* :func:`semi_implicit_euler`: second-order (x, v) trajectories from many starts (symplectic Euler);
* :func:`euler_until_rest`: explicit Euler with the ds-opt stop rule (:func:`euler_blocks_until_rest`:
  several systems at once, each with its own stop); :func:`euler_arrival_times`: only the first
  arrival at a goal of each start, each stopped once it has arrived or is overdue.

Sizes are checked against :mod:`sosdyn.limits` before anything is allocated; a trajectory
whose state or velocity stops being finite raises :class:`~sosdyn.errors.SolverError`, so
no integrator returns NaN or inf.
"""

from sosdyn.lfd.rollout.adaptive import ATOL_REL, BATCH_INTEGRATORS, INTEGRATORS, final_states, motion_scale, rollout
from sosdyn.lfd.rollout.budget import (GRID_BUDGETS, ROLLOUT_BUDGETS, BudgetExceeded, BudgetRollout,
                                       CountedField, run_with_budget)
from sosdyn.lfd.rollout.euler import (euler_arrival_times, euler_blocks_until_rest, euler_until_rest,
                                      semi_implicit_euler)
from sosdyn.lfd.rollout.events import (Field, Trajectory, WorkMeter, as_positive, as_vector,
                                       check_rollout_size, parse_events)

__all__ = [
    "ATOL_REL", "BATCH_INTEGRATORS", "INTEGRATORS", "final_states", "motion_scale", "rollout",
    "GRID_BUDGETS", "ROLLOUT_BUDGETS", "BudgetExceeded", "BudgetRollout", "CountedField", "run_with_budget",
    "euler_arrival_times", "euler_blocks_until_rest", "euler_until_rest", "semi_implicit_euler", "Field", "Trajectory", "WorkMeter", "as_positive", "as_vector",
    "check_rollout_size",
    "parse_events",
]

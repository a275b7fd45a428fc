"""DMP baseline: discrete dynamical movement primitives via ``movement_primitives``.

Transformation system (Ijspeert et al. 2013, Eq. 2.1, as implemented by
``movement_primitives.dmp.DMP``), with phase z(t) = exp(−α_z t / τ):

    τ² ÿ = α_y (β_y (g − y) − τ ẏ) + f(z),   f(z) = z Σ_i ψ_i(z) w_i / Σ_i ψ_i(z),

τ = the demonstration's duration; ``n_weights_per_dim`` is the number of basis functions
ψ_i (CDSP paper §3: 25 / 35 / 25 / 35 for BendedLine / DoubleBendedLine / Leaf_1 / Leaf_2).

Protocol: **one DMP per demonstration** (the usual reproduction protocol of the CDSP
comparison: the DMP learned from demo i reproduces demo i).  A DMP is time-indexed, so
:meth:`DMP.predict` is undefined.  In a rollout:

* the DMP used is ``demo`` if given, else the one whose demonstration starts nearest x0;
  it starts at rest at x0 with phase z = 1 and runs past τ (z → 0, the spring-damper
  settles at the goal);
* a goal change at time t calls ``configure(goal_y=new_goal)``; the phase continues;
* a push dx at time t restarts the DMP from the pushed state x(t) + dx with the remaining
  phase z(t) and the current velocity ẏ(t) (the push moves the position only).

Events are applied at the first step time ≥ their time (the grid is that of
:func:`sosdyn.lfd.rollout.rollout`); the sample at an event time shows its effect.
"""

import numpy as np
from movement_primitives.dmp import DMP as _MPDMP

from sosdyn.errors import InputError
from sosdyn.evaluation.baselines.base import MotionModel, check_int
from sosdyn.lfd.rollout import Trajectory, as_positive, check_rollout_size, parse_events


class DMP(MotionModel):
    """One movement-primitives DMP per demonstration (see the module docstring).

    Parameters
    ----------
    n_weights_per_dim : int
        Basis functions of the forcing term per dimension (> 1).
    alpha_y, beta_y : float
        Gains of the transformation system (defaults of movement_primitives: critically
        damped, α_y = 4 β_y).
    regularization : float
        Ridge coefficient of the weight regression (≥ 0).

    Learned attributes: ``weights_`` (N, n, n_weights_per_dim), ``durations_`` (N,),
    ``starts_`` (N, n), ``goal_``, ``dim_``, ``dt_``.
    """

    name = "DMP"
    time_indexed = True     # no field: evaluations run its own rollout (sosdyn.evaluation.realdata)

    def __init__(self, n_weights_per_dim=25, alpha_y=25.0, beta_y=6.25, regularization=0.0):
        self.n_weights_per_dim = n_weights_per_dim
        self.alpha_y = alpha_y
        self.beta_y = beta_y
        self.regularization = regularization

    def _primitive(self, duration, dt):
        return _MPDMP(self.dim_, execution_time=duration, dt=dt,
                      n_weights_per_dim=self.n_weights_per_dim,
                      alpha_y=self.alpha_y, beta_y=self.beta_y)

    def fit(self, demos):
        check_int(self.n_weights_per_dim, "n_weights_per_dim", minimum=2)
        as_positive(self.alpha_y, "alpha_y")
        as_positive(self.beta_y, "beta_y")
        if self.regularization != 0:
            as_positive(self.regularization, "regularization")
        demos = self._learn_frame(demos)
        weights = []
        for demo in demos:
            primitive = self._primitive(demo.duration, self.dt_)
            primitive.imitate(demo.t - demo.t[0], np.asarray(demo.pos),
                              regularization_coefficient=self.regularization)
            weights.append(primitive.get_weights().reshape(self.dim_, -1))
        self.weights_ = np.array(weights)
        self.durations_ = np.array([demo.duration for demo in demos])
        self.starts_ = np.array([demo.pos[0] for demo in demos])
        return self

    def predict(self, X):
        raise NotImplementedError(
            "A DMP is time-indexed (its forcing term depends on the phase z(t), not on x), so "
            "it has no velocity field ẋ = f(x) to predict; use rollout(x0, duration) instead.")

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(),
                demo=None):
        """Run the DMP of demonstration ``demo`` (default: start nearest ``x0``) from ``x0``.

        Pushes and goal changes follow the rules of the module docstring; the returned
        :class:`~sosdyn.lfd.rollout.Trajectory` has the grid and event log of
        :func:`sosdyn.lfd.rollout.rollout`.
        """
        x0, duration, dt, goal = self._rollout_args(x0, duration, dt, goal)
        if demo is None:
            demo = int(np.argmin(np.linalg.norm(self.starts_ - x0, axis=1)))
        demo = check_int(demo, "demo", minimum=0)
        if demo >= len(self.durations_):
            raise InputError(f"demo {demo} does not exist; the model has "
                             f"{len(self.durations_)} demonstrations (0..{len(self.durations_) - 1}).")
        events = parse_events(perturbations, goal_changes, self.dim_, duration)
        grid = np.linspace(0.0, duration, check_rollout_size(duration, dt, self.dim_))
        primitive = self._primitive(self.durations_[demo], grid[1] - grid[0])
        primitive.set_weights(self.weights_[demo])
        primitive.configure(start_y=x0, goal_y=goal)
        primitive.reset()
        primitive.initialized = True      # reset() already placed the state at x0
        pos, goals, log = np.empty((len(grid), self.dim_)), np.empty((len(grid), self.dim_)), []
        pending = iter(events)
        event = next(pending, None)
        for k, t in enumerate(grid):
            while event is not None and event[0] <= t + 1e-9 * dt:
                time, kind, vector = event
                if kind == "push":
                    before = primitive.current_y.copy()
                    primitive.current_y = before + vector
                    after = primitive.current_y
                else:
                    before = primitive.goal_y.copy()
                    primitive.configure(goal_y=vector.copy())
                    after = vector
                log.append({"kind": kind, "time": time, "before": before, "after": after.copy()})
                event = next(pending, None)
            pos[k], goals[k] = primitive.current_y, primitive.goal_y
            if k + 1 < len(grid):
                primitive.step(primitive.current_y, primitive.current_yd)
        return Trajectory(grid, pos, goals, log)

"""The common interface of the baseline motion models (docs/interfaces.md, "Motion models").

Every baseline follows the scikit-learn conventions: hyper-parameters are set in
``__init__`` and only stored there, ``fit(demos)`` learns and returns the model, and the
learned state lives in attributes whose names end in ``_``.  Inputs are checked once, at
the public boundary, by ``check_points`` / ``check_int`` below and the shared
:func:`~sosdyn.lfd.rollout.as_vector` / :func:`~sosdyn.lfd.rollout.as_positive`; they raise
:class:`~sosdyn.errors.InputError` (or :class:`~sosdyn.errors.NotFittedError`).
"""

import abc
import numbers

import numpy as np

from sosdyn.errors import InputError, NotFittedError
from sosdyn.lfd.data.demonstrations import check_demonstrations, sample_step
from sosdyn.lfd.rollout import as_positive, as_vector, rollout


def check_points(X, dim, name="X"):
    """Return ``X`` as a finite float array of shape (m, dim); one point (dim,) is accepted."""
    arr = np.asarray(X, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InputError(
            f"{name} must have shape (m, {dim}) (one point per row in the model's "
            f"{dim}-D space), got shape {np.shape(X)}.")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} contains NaN or inf; remove or repair those rows.")
    return arr


def check_int(value, name, minimum=1):
    """Return ``value`` as an int >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}.")
    return int(value)


class MotionModel(abc.ABC):
    """Base of every baseline: ``fit``, ``predict``, ``rollout`` and ``name``.

    ``fit`` (in subclasses) calls :meth:`_learn_frame` first, which records the
    dimension ``dim_``, the training goal ``goal_`` (mean last position) and the median
    sampling step ``dt_`` used as the default rollout step.
    """

    name = "motion model"

    @abc.abstractmethod
    def fit(self, demos):
        """Learn from :class:`~sosdyn.lfd.data.demonstrations.Demonstrations`; return ``self``."""

    @abc.abstractmethod
    def predict(self, X):
        """ẋ at the rows of ``X`` (m, n) for the training goal."""

    @abc.abstractmethod
    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()):
        """A :class:`~sosdyn.lfd.rollout.Trajectory` from ``x0`` (``dt`` default: ``dt_``)."""

    def _learn_frame(self, demos):
        demos = check_demonstrations(demos)
        self.dim_ = demos.dim
        self.goal_ = np.asarray(demos.goal, dtype=float)
        self.dt_ = sample_step(demos)
        return demos

    def _check_fitted(self):
        if not hasattr(self, "goal_"):
            raise NotFittedError(
                f"This {self.name} model is not fitted yet; call fit(demos) first.")

    def _rollout_args(self, x0, duration, dt, goal):
        """Checked (x0, duration, dt, goal) with the defaults of the training frame."""
        self._check_fitted()
        x0 = as_vector(x0, self.dim_, "x0")
        duration = as_positive(duration, "duration")
        dt = self.dt_ if dt is None else as_positive(dt, "dt")
        if dt > duration:
            raise InputError(f"dt = {dt:g} is larger than duration = {duration:g}; "
                             "pass a longer duration or a smaller dt.")
        goal = self.goal_.copy() if goal is None else as_vector(goal, self.dim_, "goal")
        return x0, duration, dt, goal


class AutonomousModel(MotionModel):
    """A time-invariant field ẋ = f(x; goal); subclasses implement :meth:`field`.

    ``predict(X)`` is the field at the training goal, and ``rollout`` integrates the field
    with :func:`sosdyn.lfd.rollout.rollout` (pushes and goal changes handled there).
    """

    @abc.abstractmethod
    def field(self, X, goal):
        """ẋ at the rows of ``X`` (m, n) for the goal ``goal`` (n,); no input checks.

        This is the :data:`sosdyn.lfd.rollout.Field` that :meth:`rollout` integrates.
        """

    def predict(self, X):
        """ẋ = f(x) at the rows of ``X`` (m, n), for the training goal."""
        self._check_fitted()
        return self.field(check_points(X, self.dim_), self.goal_)

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()):
        """Integrate the field from ``x0``; see :func:`sosdyn.lfd.rollout.rollout`."""
        x0, duration, dt, goal = self._rollout_args(x0, duration, dt, goal)
        return rollout(self.field, x0, duration=duration, dt=dt, goal=goal,
                       perturbations=perturbations, goal_changes=goal_changes)

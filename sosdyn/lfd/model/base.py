"""One interface, three families: what every motion model of sosdyn implements, so that a caller (the
``sosdyn`` command, a report) never asks which family it holds.

The families: :class:`~.cdsp.CDSP` (first order, xdot = f(x)), :class:`~.pose.PoseCDSP` (position and
orientation) and :class:`~.second_order.SecondOrderCDSP` (xddot = a(x, xdot)). Each subclass of
:class:`MotionModel` names its file format (``file_format``, ``file_version``) and is registered
under it when its class is defined (:data:`FAMILIES`, :func:`family_of`): :func:`~.files.load_model`
reads any model file through it. :func:`family_for` picks the family that fits a set of
demonstrations (pose demonstrations: the pose model; ``order`` 2: the second-order model).

The methods, the same in every family (a family's own keywords are refused by the others with an
InputError saying what they are for):

    fit(demos) -> self;  score(demos) -> one row per demonstration (reproduction from its start)
    predict(...)          velocities (first order, pose chart) or accelerations (second order)
    rollout(x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None, ...)
        -> a trajectory with ``t``, ``states`` (rows as :meth:`layout` ``columns``) and ``goal_history``
    predictor(max_speed=None, ...) -> a one-state evaluator for control loops
    verify(n_samples=None, seed=None) -> the certificate's independent check (``.passed``)
    excursion_bound(x0, goal=None, ...) -> a certified bound on max_t |x(t) - goal| (inf: none known)
    to_python(max_speed=None, ...), to_cpp(namespace=None, max_speed=None, ...), export(target, ...)
    save(path, key=None); content() / from_content(content): the model file's fields
    layout() -> the names of a start state's, a push's, a goal's and a rollout row's numbers
    reproductions(demos=None, duration=None) -> what a figure of the model shows
    summary() -> lines about the certificate and the fit, for people
    iteration_cap(rows) -> a sentence when the history rows of one fit show it stopped at max_iter

and the attributes ``name``, ``certified_``, ``verification_``, ``history_``, ``units_``, ``columns_``,
``only_with`` (the parameters that apply only when another parameter has a given value).
"""
from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from sosdyn.errors import InputError
from ..data.crossing import crossing_warning, find_crossings
from ..data.demonstrations import check_demonstrations, position_names
from ..data.pose import PoseDemonstrations
from ..data.preprocess import preprocess
from .content import POSE_FORMAT, SECOND_ORDER_FORMAT
from .fileformat import FORMAT, write_model_file

#: Every family, by the format of its model files (filled as the families are defined).
FAMILIES: dict[str, type[MotionModel]] = {}
EXPORT_TARGETS = ("python", "cpp")


@dataclass(frozen=True)
class Layout:
    """How a model's states are written as numbers (``sosdyn rollout``'s options, a rollout's CSV):
    the names of the numbers of a start state, of each accepted push vector, of a goal, and of a
    rollout row after the time (``columns``)."""

    start: tuple[str, ...]
    pushes: tuple[tuple[str, ...], ...]
    goal: tuple[str, ...]
    columns: tuple[str, ...]


@dataclass
class Reproductions:
    """What a figure of a model shows: demonstrations and the model's rollouts from their starts
    (each with ``t`` and ``pos``, and ``quat`` for poses), the goal position, the position axes'
    names and units, and the velocity field X -> Xdot over positions when the model has one
    (first order: streamlines in 2-D)."""

    demos: list
    runs: list
    goal: np.ndarray
    names: tuple[str, ...]
    units: str
    field: Callable | None = None


class MotionModel(ABC):
    """The interface of every model family (module docstring)."""

    name: ClassVar[str]
    file_format: ClassVar[str]
    file_version: ClassVar[int]
    #: Can it follow demonstrations that cross themselves (a state that carries more than the position)?
    follows_crossings: ClassVar[bool] = False
    #: Parameters that apply only when another parameter has a value, {name: (other, value)}: set to
    #: anything but its default otherwise, the model refuses it (a caller can name the remedy first).
    only_with: ClassVar[dict[str, tuple[str, object]]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "file_format" in cls.__dict__:
            FAMILIES[cls.file_format] = cls

    # ------------------------------------------------------------------ building and fitting
    @classmethod
    def preset(cls, name: str, **overrides) -> MotionModel:
        """An unfitted model with the parameters of preset ``name``; a family without presets refuses."""
        raise InputError(f"presets are first-order CDSP parameter sets; {cls.__name__} has none. Try: its "
                         "parameters directly.")

    @abstractmethod
    def get_params(self) -> dict:
        """The model's parameters by name (what its constructor takes)."""

    @classmethod
    def prepare(cls, demos, smooth_window="auto", trim_rest=True, align="auto", max_shift=None):
        """(demos preprocessed and checked for this family, notes, warnings): the result of
        :func:`~sosdyn.lfd.data.preprocess.preprocess`, what it did (one line each) and, for a family
        that cannot follow crossing demonstrations, the crossing warning (:mod:`~sosdyn.lfd.data.crossing`)."""
        result, report = preprocess(demos, smooth_window=smooth_window, trim_rest=trim_rest, align=align,
                                    max_shift=max_shift)
        message = None if cls.follows_crossings else crossing_warning(find_crossings(result), demos.units)
        notes = [f"preprocess: {line}" for line in report.lines(demos.units)]
        return check_demonstrations(result), notes, [message] if message else []

    @abstractmethod
    def fit(self, demos) -> MotionModel:
        """Learn from demonstrations; returns self."""

    @abstractmethod
    def score(self, demos) -> list[dict]:
        """Per demonstration, its reproduction from its start (:func:`~sosdyn.lfd.rollout.quality.reproduction_rows`)."""

    @abstractmethod
    def summary(self) -> list[str]:
        """Lines about the fitted model for people: the certificate's numbers first."""

    @abstractmethod
    def iteration_cap(self, rows: list[dict]) -> str | None:
        """``stopped at max_iter=20 with relative change 3.1e-04 > tol=0.0001`` when ``rows``, the history
        rows of one fit as ``progress`` receives them (one warp candidate or corrective round), show that
        it used all ``max_iter`` iterations with the cost still changing by more than ``tol``; None otherwise."""

    # ------------------------------------------------------------------ motion
    @abstractmethod
    def predict(self, *states):
        """The model's derivative at states (velocities, or accelerations for second order)."""

    @abstractmethod
    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None):
        """Integrate from x0 for ``duration`` s with pushes, goal changes and a speed limit."""

    @abstractmethod
    def predictor(self, max_speed=None):
        """A one-state evaluator for control loops."""

    @abstractmethod
    def verify(self, n_samples=None, seed=None):
        """The certificate's independent check (a report with ``passed``)."""

    @abstractmethod
    def excursion_bound(self, x0, goal=None) -> float:
        """A certified bound on max_t |x(t) - goal| (positions, data units) from the start x0."""

    @abstractmethod
    def layout(self) -> Layout:
        """The names of the numbers of a start state, a push, a goal and a rollout row."""

    @abstractmethod
    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the demonstrations' starts (or the model's own), for a figure."""

    # ------------------------------------------------------------------ code and files
    @abstractmethod
    def to_python(self, max_speed=None) -> str:
        """A standalone Python module (numpy only; scipy for poses) evaluating the model."""

    @abstractmethod
    def to_cpp(self, namespace=None, max_speed=None) -> str:
        """A header-only C++17 evaluator of the model."""

    def export(self, target: str, **options) -> str:
        """The source of the model for ``target`` ("python" or "cpp"), options as :meth:`to_python` /
        :meth:`to_cpp` take them."""
        if target not in EXPORT_TARGETS:
            raise InputError(f"unknown export target {target!r:.40}. Try: one of {', '.join(EXPORT_TARGETS)}.")
        return self.to_python(**options) if target == "python" else self.to_cpp(**options)

    @abstractmethod
    def content(self) -> dict:
        """The model file's fields besides ``format`` and ``version`` (:mod:`.content`)."""

    @classmethod
    @abstractmethod
    def from_content(cls, content: dict) -> MotionModel:
        """The model (not yet verified) from a file's checked fields; ModelFileError naming the first bad one."""

    def save(self, path, key=None) -> Path:
        """Write the model file (JSON, checksummed, atomically; signed with ``key``, default
        $SOSDYN_MODEL_KEY); :func:`sosdyn.load_model` reads it."""
        return write_model_file({"format": self.file_format, "version": self.file_version, **self.content()},
                                path, key)

    def refuse(self, other: dict, method: str) -> None:
        """InputError for keywords ``other`` given to ``method`` that this family does not take
        (another family's, such as v0 or max_angular_speed, or none's), naming who takes them."""
        if not other:
            return
        name = sorted(other)[0]
        owners = [cls.__name__ for cls in FAMILIES.values()
                  if name in inspect.signature(getattr(cls, method)).parameters]
        whose = f"{' and '.join(owners)}.{method} takes it" if owners else "no model takes it"
        raise InputError(f"{name} does not apply to a {type(self).__name__} model ({whose}). Try: drop it.")

    def accept(self, report) -> None:
        """Record the check a loaded file passed: ``verification_`` and ``certified_``."""
        self.verification_, self.certified_ = report, True

    def names(self) -> tuple[str, ...]:
        """The names of the position coordinates (the data's columns, or x1..xn)."""
        return position_names(self.columns_, len(self.goal_))


def family_of(fmt) -> type[MotionModel] | None:
    """The family whose model files have the format ``fmt`` (None for an unknown format)."""
    return FAMILIES.get(fmt) if isinstance(fmt, str) else None


def family_for(demos, order: int = 1) -> type[MotionModel]:
    """The family that learns ``demos``: the pose model for pose demonstrations, the second-order
    model for ``order`` 2, else the first-order CDSP; InputError for an order that does not exist."""
    if order not in (1, 2):
        raise InputError(f"order must be 1 (xdot = f(x)) or 2 (xddot = a(x, xdot)), got {order!r}.")
    pose = isinstance(demos, PoseDemonstrations)
    if pose and order == 2:
        raise InputError("a second-order pose model does not exist yet. Try: order 1 for these pose "
                         "demonstrations, or order 2 on their positions (--columns x,y,z).")
    return FAMILIES[POSE_FORMAT if pose else SECOND_ORDER_FORMAT if order == 2 else FORMAT]

"""Demonstrations of point-to-point motions: the containers, velocity estimates and checks.

A demonstration is a sampled trajectory ``t_k, x_k, xdot_k`` (k = 0..T-1) that ends at the
goal. Positions are in the data's units (mm for LASA), velocities in units per second.
Loaders: :mod:`sosdyn.lfd.data.lasa` (the LASA handwriting set), :mod:`sosdyn.lfd.data.files`
(CSV / NPY files).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.columns import COLUMNS_HINT

MIN_SAMPLES = 10
#: A demonstration whose positions stay within STILL_ULPS round-off units (eps x its largest |coordinate|)
#: of its first sample does not move: what is left is round-off, and a model of it is a model of noise.
STILL_ULPS = 1000.0
#: The largest |position| or |velocity| accepted (data units, per s): their squares and cubes (a cubic
#: field's terms) must stay far from float's overflow at 1.8e308.
MAX_MAGNITUDE = 1e100
GOAL_TOL_FRACTION = 0.05
MAX_UNITS_CHARS = 32           # the units' name, e.g. 'mm' (a model file holds it)
#: Besides letters and digits (any script: 'µm', 'm²'), the only characters a units' name may hold:
#: it reaches model files, plot labels and generated code, so no quotes, backslashes, ':', '=' or '#'.
UNITS_SYMBOLS = " /.-_^*()%°·"
_SG_WINDOW, _SG_ORDER = 9, 3


def _read_only(values, what: str) -> np.ndarray:
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DemonstrationError(
            f"{what} is not a numeric array ({exc}); pass arrays of floats."
        ) from exc
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class Demonstration:
    """One demonstration: ``t`` (T,) in s, ``pos`` (T, n), ``vel`` (T, n) = d pos / dt.

    The arrays are stored as read-only float copies; :func:`check_demonstrations` validates
    them. ``source`` says where the demonstration came from (used in error messages).
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    source: str = ""

    def __post_init__(self):
        for field in ("t", "pos", "vel"):
            value = _read_only(getattr(self, field), f"Demonstration {self.source!r} field {field!r}")
            object.__setattr__(self, field, value)

    @classmethod
    def from_positions(cls, t, pos, source: str = "") -> Demonstration:
        """A demonstration whose velocities are estimated by :func:`estimate_velocity`."""
        return cls(t, pos, estimate_velocity(t, pos), source)

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` in seconds."""
        return float(self.t[-1] - self.t[0])


def units_problem(units) -> str | None:
    """None if ``units`` is a valid units' name -- a string of at most MAX_UNITS_CHARS characters,
    each a letter, a digit or one of UNITS_SYMBOLS -- else what is wrong (a phrase after "units")."""
    if not isinstance(units, str):
        return f"must be a string, got {type(units).__name__}"
    bad = sorted({c for c in units if not (c.isalnum() or c in UNITS_SYMBOLS)})
    if len(units) > MAX_UNITS_CHARS or bad:
        extra = f" (not {''.join(bad)!r:.40})" if bad else ""
        return (f"must be at most {MAX_UNITS_CHARS} characters, each a letter, a digit or one of "
                f"{UNITS_SYMBOLS.strip()!r}{extra}; got {units!r:.60}")
    return None


class Demonstrations(Sequence):
    """An immutable sequence of :class:`Demonstration` sharing a ``name`` and ``units``.

    ``goal_tol`` (None or a number >= 0) is the end-point tolerance the set was accepted with
    (:func:`check_demonstrations`): a later check of the same set (``CDSP.fit``) uses it too.
    ``columns`` (None or n names, each as :func:`units_problem` allows): the names of the position
    columns as read (a file's header); a fitted model keeps them (plot axes, rollout CSVs, exports)."""

    __slots__ = ("_demos", "_name", "_units", "_goal_tol", "_columns")

    def __init__(self, demos, name: str = "", units: str = "", goal_tol: float | None = None,
                 columns=None):
        demos = tuple(demos)
        for i, demo in enumerate(demos):
            if not isinstance(demo, Demonstration):
                raise InputError(
                    f"Item {i} is a {type(demo).__name__}, not a Demonstration; build it with "
                    "Demonstration(t, pos, vel) or Demonstration.from_positions(t, pos)."
                )
        units = str(units)
        problem = units_problem(units)
        if problem:
            raise InputError(f"units {problem}. Try: a short name such as 'm' or 'mm'.")
        self._demos, self._name, self._units = demos, str(name), units
        self._goal_tol = _check_goal_tol(goal_tol)
        self._columns = check_columns(columns, demos[0].pos.shape[-1] if demos and columns is not None else None)

    name = property(lambda self: self._name, doc="Name of the set, e.g. 'Leaf_1' or a file stem.")
    units = property(lambda self: self._units, doc="Position units, e.g. 'mm' for LASA.")
    goal_tol = property(lambda self: self._goal_tol,
                        doc="End-point tolerance the set was accepted with (None: the default).")
    columns = property(lambda self: self._columns, doc="Names of the position columns (None: unnamed).")

    def __len__(self) -> int:
        return len(self._demos)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return Demonstrations(self._demos[index], self._name, self._units, self._goal_tol, self._columns)
        return self._demos[index]

    def __repr__(self) -> str:
        dim = self._demos[0].pos.shape[-1] if self._demos else None
        return f"Demonstrations({self._name!r}, {len(self)} demos, dim={dim}, units={self._units!r})"

    def _require_demos(self):
        if not self._demos:
            raise DemonstrationError(f"Demonstrations {self._name!r} is empty; load at least one.")

    @property
    def dim(self) -> int:
        """State dimension n."""
        self._require_demos()
        return int(self._demos[0].pos.shape[1])

    @property
    def goal(self) -> np.ndarray:
        """Mean of the demonstrations' last positions, shape (n,)."""
        self._require_demos()
        return np.mean([d.pos[-1] for d in self._demos], axis=0)

    def stacked(self) -> tuple[np.ndarray, np.ndarray]:
        """All samples stacked: ``X`` and ``Xdot``, each (sum of T, n)."""
        self._require_demos()
        return np.vstack([d.pos for d in self._demos]), np.vstack([d.vel for d in self._demos])

    def subsample(self, step: int) -> Demonstrations:
        """Keep every ``step``-th sample of each demonstration, and always its last one (the goal)."""
        if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 1:
            raise InputError(f"subsample step must be an integer >= 1, got {step!r}.")
        out = []
        for d in self._demos:
            idx = np.arange(0, len(d.t), step)
            if idx[-1] != len(d.t) - 1:
                idx = np.append(idx, len(d.t) - 1)
            out.append(Demonstration(d.t[idx], d.pos[idx], d.vel[idx], d.source))
        return Demonstrations(out, self._name, self._units, self._goal_tol, self._columns)


def check_columns(columns, dim: int | None) -> tuple[str, ...] | None:
    """``columns`` as a tuple of ``dim`` distinct names (None stays None); InputError otherwise. A name
    reaches model files, plot labels and generated code, so it obeys the units' rule
    (:func:`units_problem`) and is not empty."""
    if columns is None:
        return None
    if isinstance(columns, (str, bytes)) or not hasattr(columns, "__iter__"):
        raise InputError(f"columns must be a sequence of names, got {columns!r:.60}.")
    names = tuple(columns)
    problem = next((f"{name!r:.40} {units_problem(name)}" for name in names if units_problem(name)), None) or \
        next((f"{name!r} is empty" for name in names if name == ""), None)
    if problem or len(set(names)) != len(names) or (dim is not None and len(names) != dim):
        raise InputError(f"columns must be {dim if dim is not None else 'n'} distinct names of the position "
                         f"columns, got {names!r:.80}{': ' + problem if problem else ''}.")
    return names


def position_names(columns, dim: int) -> tuple[str, ...]:
    """The names of the ``dim`` position coordinates: ``columns``, or x1..xn when they are unnamed."""
    return tuple(columns) if columns is not None else tuple(f"x{i + 1}" for i in range(dim))


def _check_goal_tol(goal_tol) -> float | None:
    if goal_tol is None:
        return None
    if isinstance(goal_tol, bool) or not isinstance(goal_tol, (int, float, np.number)) or not goal_tol >= 0:
        raise InputError(f"goal_tol must be a number >= 0 (or None: 5% of the data scale), got {goal_tol!r}.")
    return float(goal_tol)


def time_problem(t: np.ndarray) -> str | None:
    """Why ``t`` is not a finite, strictly increasing time axis, as a sentence (None if it is)."""
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        return f"time t is not finite (NaN or inf) at sample {bad[0]} of {len(t)}"
    steps = np.diff(t)
    back = np.flatnonzero(steps < 0) if (steps < 0).any() else np.flatnonzero(steps == 0)   # going back first
    if back.size:
        k = back[0] + 1
        return (f"time is not strictly increasing at sample {k} of {len(t)} "
                f"(t[{k - 1}] = {t[k - 1]:g}, t[{k}] = {t[k]:g}); sort the samples (load_demos merges samples "
                "that share a stamp, but refuses time that goes back)")
    return None


def merge_repeated_stamps(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, int]:
    """One sample per time stamp where a non-decreasing ``t`` repeats one (the logs of mice and robots
    do): the rows sharing a stamp become one, their mean -- their common row when they are identical.
    Returns (t, values, identical rows dropped, differing rows averaged in); ``t`` that decreases
    somewhere, or repeats nothing, is returned as it is (:func:`time_problem` judges it)."""
    steps = np.diff(t)
    if not (steps == 0).any() or (steps < 0).any() or not np.isfinite(t).all():
        return t, values, 0, 0
    starts = np.r_[0, np.flatnonzero(steps > 0) + 1]
    counts = np.diff(np.r_[starts, len(t)])
    first = values[starts]
    differs = np.logical_or.reduceat((values != np.repeat(first, counts, axis=0)).any(axis=1), starts)
    merged = np.where(differs[:, None], np.add.reduceat(values, starts, axis=0) / counts[:, None], first)
    extra = counts - 1
    return t[starts], merged, int(extra[~differs].sum()), int(extra[differs].sum())


def estimate_velocity(t, pos) -> np.ndarray:
    """Velocities ``d pos / dt`` by smoothed finite differences, shape (T, n).

    On a uniform time grid: the Savitzky-Golay derivative (local cubic least-squares fit over
    a 9-sample window, shorter for short demos; exact for cubic motions). On a non-uniform
    grid or with fewer than 5 samples: second-order finite differences
    ``np.gradient(pos, t, edge_order=2)`` (exact for quadratic motions).
    """
    from scipy.signal import savgol_filter   # scipy.signal is slow to import; only here
    t, pos = np.asarray(t, dtype=float), np.asarray(pos, dtype=float)
    if t.ndim != 1 or pos.ndim != 2 or len(t) != len(pos) or len(t) < 3:
        raise DemonstrationError(
            f"Cannot estimate velocities from t {t.shape} and pos {pos.shape}; "
            "need t (T,) and pos (T, n) with the same T >= 3."
        )
    problem = time_problem(t)
    if problem:
        raise DemonstrationError(f"Cannot estimate velocities: {problem}.")
    steps = np.diff(t)
    window = min(_SG_WINDOW, len(t) if len(t) % 2 else len(t) - 1)
    if window > _SG_ORDER + 1 and np.allclose(steps, steps.mean(), rtol=1e-6, atol=0):
        return savgol_filter(pos, window, _SG_ORDER, deriv=1, delta=steps.mean(), axis=0, mode="interp")
    return np.gradient(pos, t, axis=0, edge_order=2)


def _label(i: int, demo: Demonstration, name: str) -> str:
    text = f"demo {i}"
    if demo.source:
        text += f" ({demo.source})"
    return text + (f" of {name!r}" if name else "")


def _check_one(demo: Demonstration, label: str) -> None:
    t, pos, vel = demo.t, demo.pos, demo.vel
    if t.ndim != 1 or pos.ndim != 2 or vel.shape != pos.shape or len(t) != len(pos) or pos.shape[1] < 1:
        raise DemonstrationError(
            f"{label}: shapes do not fit together: t {t.shape}, pos {pos.shape}, vel {vel.shape}; "
            "expected t (T,), pos (T, n) and vel (T, n) with the same T and n >= 1."
        )
    if len(t) < MIN_SAMPLES:
        raise DemonstrationError(
            f"{label}: only {len(t)} samples; at least {MIN_SAMPLES} are needed. "
            "Record the motion at a higher rate or drop this demonstration."
        )
    for what, values in (("pos", pos), ("vel", vel)):
        bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
        if bad.size:
            raise DemonstrationError(
                f"{label}: {what} is not finite (NaN or inf) at sample {bad[0]} of {len(t)} "
                f"({bad.size} bad samples); remove or interpolate them."
            )
    problem = time_problem(t)
    if problem:
        raise DemonstrationError(f"{label}: {problem}.")
    for what, values, hint in (("positions", pos, "other units for the positions"),
                               ("velocities", vel, "the time step in s (--dt / dt=) or the time units (--time-units "
                                                   "/ time_units=)")):
        top = float(np.abs(values).max())
        if top > MAX_MAGNITUDE:
            raise DemonstrationError(
                f"{label}: the {what} reach {top:.3g} (positions up to {float(np.abs(pos).max()):.3g} over "
                f"{demo.duration:.3g} s), above {MAX_MAGNITUDE:g}: the fit's squares and products of them would "
                f"overflow float. Try: {hint}.")
    problem = still_problem(pos)
    if problem:
        raise DemonstrationError(f"{label}: {problem}")


def still_coordinates(pos: np.ndarray) -> np.ndarray:
    """Which coordinates of the positions ``pos`` (T, n) do not move: every sample within STILL_ULPS
    round-off units (eps x the coordinate's largest magnitude) of the first. (n,) booleans."""
    moved = np.abs(pos - pos[0]).max(axis=0)
    return moved <= STILL_ULPS * np.finfo(float).eps * np.abs(pos).max(axis=0)


def still_problem(pos: np.ndarray) -> str | None:
    """Why the positions ``pos`` (T, n) are not a motion -- no coordinate moves
    (:func:`still_coordinates`) -- as a sentence with a hint; None when they move."""
    if not still_coordinates(pos).all():
        return None
    return (f"the positions do not move (every sample within {float(np.abs(pos - pos[0]).max()):.3g} of the "
            f"first, round-off at their magnitude {float(np.abs(pos).max()):.3g}): there is no motion to learn. "
            f"Try: check that the position columns are the moving ones ({COLUMNS_HINT}), or drop this "
            "demonstration.")


def check_demonstrations(demos, *, goal_tol: float | None = None, ends: bool = True) -> Demonstrations:
    """Validate demonstrations for learning and return them as :class:`Demonstrations`.

    Raises :class:`DemonstrationError` for: no demonstrations; shapes that disagree (t (T,),
    pos and vel (T, n)); fewer than ``MIN_SAMPLES`` (10) samples; positions that do not move
    (:func:`still_problem`); positions or velocities above MAX_MAGNITUDE; non-finite values (the
    message names the demo and the first bad sample); time not strictly increasing;
    dimensions that differ between demos; end points that disagree, i.e. a spread
    ``max_i ||x_i(T_i) - mean_j x_j(T_j)||`` above ``goal_tol`` (same units as the data;
    default: the tolerance ``demos`` was accepted with (``Demonstrations.goal_tol``), else 5 %
    of the diagonal of the bounding box of all positions; ``np.inf`` disables). The returned
    set records the tolerance used, so checking it again (``CDSP.fit``) accepts it again.

    The ends are one acceptance rule with one home, applied after preprocessing: the loaders
    (:func:`~.files.load_demos`, :func:`~.datasets.load_dataset`) check everything else and pass
    ``ends=False`` (recording ``goal_tol``), :func:`~.preprocess.preprocess` may align the ends, and
    every model's ``prepare`` and ``fit`` check them here -- the same in Python and in ``sosdyn fit``.
    """
    try:
        items = list(demos)
    except TypeError as exc:
        raise InputError(f"Expected a sequence of Demonstration, got {type(demos).__name__}.") from exc
    name = getattr(demos, "name", "")
    goal_tol = _check_goal_tol(getattr(demos, "goal_tol", None) if goal_tol is None else goal_tol)
    demos = Demonstrations(items, name, getattr(demos, "units", ""), goal_tol, getattr(demos, "columns", None))
    if not items:
        raise DemonstrationError(f"No demonstrations in {name or 'the input'}; provide at least one.")
    for i, demo in enumerate(items):
        _check_one(demo, _label(i, demo, name))
    dims = [d.pos.shape[1] for d in items]
    for i, n in enumerate(dims):
        if n != dims[0]:
            raise DemonstrationError(
                f"{_label(i, items[i], name)} has dimension {n} but demo 0 has {dims[0]}; "
                "all demonstrations must live in the same space."
            )
    if not ends:
        return demos
    all_pos = np.vstack([d.pos for d in items])
    diagonal = float(np.linalg.norm(all_pos.max(axis=0) - all_pos.min(axis=0)))
    if goal_tol is None:
        goal_tol = GOAL_TOL_FRACTION * diagonal
    spread = end_distances(items)[1]
    worst = int(np.argmax(spread))
    if spread[worst] > goal_tol:
        raise DemonstrationError(
            f"{_label(worst, items[worst], name)} ends {spread[worst]:.4g} {demos.units or 'units'} "
            f"from the mean end point, more than goal_tol = {goal_tol:.4g}; the demonstrations do "
            f"not share a goal. Try: align the ends first (sosdyn.preprocess(demos), as sosdyn fit does unless "
            f"--align-ends off), trim or drop that demo, or a larger goal_tol (e.g. {1.1 * spread[worst]:.3g}; "
            "sosdyn fit --goal-tol)."
        )
    return demos


def end_distances(demos) -> tuple[np.ndarray, np.ndarray]:
    """(g, d): the mean end point g = mean_i x_i(T_i) and each end's distance d_i = ||x_i(T_i) - g||."""
    ends = np.array([d.pos[-1] for d in demos])
    goal = ends.mean(axis=0)
    return goal, np.linalg.norm(ends - goal, axis=1)


def sample_step(demos: Demonstrations) -> float:
    """The data's time step: the median of every demonstration's sample intervals."""
    return float(np.median(np.concatenate([np.diff(d.t) for d in demos])))


def resample_in_time(t: np.ndarray, pos: np.ndarray, n_points: int) -> np.ndarray:
    """The curve pos (T, n), sampled at the increasing times t, at n_points instants equidistant in
    time from t[0] to t[-1] (linear interpolation)."""
    s = np.linspace(t[0], t[-1], n_points)
    return np.column_stack([np.interp(s, t, pos[:, i]) for i in range(pos.shape[1])])

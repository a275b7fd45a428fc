"""Demonstrations from CSV and NPY files: layout detection, parsing and :func:`load_demos`.

Errors name the file, the line and how the file was read (delimiter, decimal mark).
"""

from __future__ import annotations

import csv
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.limits import check_bytes, format_bytes
from sosdyn.lfd.data.columns import (COLUMNS_HINT, TIME_UNITS, check_duration, check_time_units, parse_columns,
                                    refuse_unclaimed, suggest_columns, time_header_names, time_unit)
from sosdyn.lfd.data.demonstrations import (Demonstration, Demonstrations, check_demonstrations, still_coordinates,
                                            merge_repeated_stamps, time_problem, units_problem)
from sosdyn.lfd.data.pose import PoseDemonstrations, is_pose_file, load_pose_demos

_AXES = ("x", "y", "z")
_DEFAULT_DEMO_NAME = "demo"
_SNIFF_LINES = 50
#: Working memory of reading a file, per byte of it: a text cell becomes a Python string (measured 8x
#: for 25-character numbers, about 20x for 4-character ones); an .npy array of int8 becomes float64 (8x).
READ_BYTES_PER_BYTE = 24
_DELIMITER_NAMES = {",": "comma", ";": "semicolon", "\t": "tab", None: "whitespace"}
_DECIMAL_COMMA = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
_NO_TIME_HINT = ("name the time column t, time or timestamp (t_ms / t_us for milli- / microseconds), or "
                 "give the sampling step if the samples are equally spaced: --dt STEP (sosdyn fit / plot) "
                 "or dt=STEP (load_demos), in s")


@dataclass(frozen=True)
class _Table:
    """A file's cells (rows x columns: str, or float for .npy), its header and how it was split.

    ``header``: lower-case column names, or None; ``lines``: the file line of each row (for
    messages); ``delimiter``: ',', ';', '\t', None (runs of whitespace) or 'npy';
    ``decimal``: '.' or ','.
    """

    path: Path
    header: list[str] | None
    cells: np.ndarray
    lines: np.ndarray
    delimiter: str | None
    decimal: str

    @property
    def layout(self) -> str:
        return _layout(self.delimiter, self.decimal, self.cells.shape[1])


def _layout(delimiter: str | None, decimal: str, width: int) -> str:
    """How a file was read, for messages: "delimiter ';' (semicolon), decimal comma"."""
    if delimiter == "npy":
        return "a .npy array"
    if width <= 1:
        text = "no delimiter found (one column; tried comma, semicolon, tab and whitespace)"
    else:
        text = f"delimiter {delimiter or ' '!r} ({_DELIMITER_NAMES[delimiter]})"
    return text + (", decimal comma" if decimal == "," else "")


def _number(text: str, decimal: str) -> float | None:
    """The number a cell holds, or None; with decimal ',' a '.' is refused (thousands separator?)."""
    if decimal == ",":
        if "." in text:
            return None
        text = text.replace(",", ".")
    try:
        return float(text)
    except ValueError:
        return None


def _sniff(lines: list[str]) -> str | None:
    """The column delimiter of the first ``_SNIFF_LINES`` lines.

    ';' or tab if every line has one; None (runs of whitespace) if every line splits on
    whitespace into the same number (> 1) of fields and every comma sits between two digits
    (decimal commas, "0,5 1,25"); else ',' if any line has a comma; else None.
    """
    sample = lines[:_SNIFF_LINES]
    for delimiter in (";", "\t"):
        if all(delimiter in line for line in sample):
            return delimiter
    widths = {len(line.split()) for line in sample}
    text = "\n".join(sample)
    if len(widths) == 1 and widths.pop() > 1 and not re.search(r"(?<!\d),|,(?!\d)", text):
        return None
    return "," if "," in text else None


def _split(lines: list[str], delimiter: str | None) -> list[list[str]]:
    if delimiter is None:
        return [line.split() for line in lines]
    return [[c.strip() for c in row] for row in csv.reader(lines, delimiter=delimiter)]


def _read_npy(path: Path) -> _Table:
    try:
        cells = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise DemonstrationError(f"{path}: not a readable numeric .npy array ({exc}).") from exc
    if cells.ndim != 2 or not np.issubdtype(cells.dtype, np.number):
        raise DemonstrationError(
            f"{path}: expected a 2-D numeric array T x (1+n) or T x (1+2n), "
            f"got shape {cells.shape} dtype {cells.dtype}."
        )
    return _Table(path, None, cells.astype(float), np.arange(1, len(cells) + 1), "npy", ".")


def _read_table(path: Path) -> _Table:
    """The cells of a .npy or text file; text: delimiter and decimal mark detected, header
    taken only from a first row none of whose cells is a number (so a data row never is one).
    Blank lines and lines starting with '#' are skipped. The memory of reading it, READ_BYTES_PER_BYTE x
    the file's size, is checked against ``max_bytes`` (:mod:`sosdyn.limits`) first."""
    check_bytes(path.stat().st_size * READ_BYTES_PER_BYTE, f"reading {path} ({format_bytes(path.stat().st_size)})",
                "a smaller file (every k-th row: sosdyn subsamples long demonstrations anyway)")
    if path.suffix.lower() == ".npy":
        return _read_npy(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DemonstrationError(f"{path}: not a UTF-8 text file ({exc}); save it as CSV text.") from exc
    numbered = [(k + 1, line) for k, line in enumerate(text.splitlines())
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise DemonstrationError(f"{path}: the file has no data rows.")
    lines = np.array([k for k, _ in numbered])
    delimiter = _sniff([line for _, line in numbered])
    rows = _split([line for _, line in numbered], delimiter)
    commas_in_cells = '"' in text if delimiter == "," else "," in text     # a ',' cell must be quoted
    decimal = "," if commas_in_cells and any(_DECIMAL_COMMA.fullmatch(c) for r in rows for c in r) else "."
    if len(rows) > 1 and all(len(r) == 1 for r in rows) and _number(rows[1][0], decimal) is None:
        raise DemonstrationError(
            f"{path}: line {lines[0]} reads {rows[0][0]!r}: {_layout(delimiter, decimal, 1)}. Try: "
            "separate the columns by ',', ';', tab or spaces.")
    header = None
    if not any(_number(c, decimal) is not None for c in rows[0]):
        header, rows, lines = [c.lower() for c in rows[0]], rows[1:], lines[1:]
    width = len(header) if header else len(rows[0]) if rows else 0
    layout = _layout(delimiter, decimal, width)
    if not rows:
        raise DemonstrationError(f"{path}: the file has no data rows (read with {layout}).")
    for line, row in zip(lines, rows):
        if len(row) != width:
            first = "the header" if header else f"line {lines[0]}"
            raise DemonstrationError(
                f"{path}: rows have different numbers of columns: line {line} has {len(row)}, {first} "
                f"has {width} (read with {layout}). Try: the same columns on every line"
                + ("; with decimal commas separate the columns by ';' or tab" if delimiter == "," else "")
                + ".")
    return _Table(path, header, np.array(rows, dtype=object).reshape(len(rows), width), lines,
                  delimiter, decimal)


def _column_index(spec, table: _Table, what: str) -> int:
    """The index of the column ``spec``: a header name (any case), or an index (an int, or a string of
    digits that is not a header name: ``--columns 1,2``)."""
    header, ncols = table.header, table.cells.shape[1]
    if isinstance(spec, str) and (header is None or spec.lower() not in header) and re.fullmatch(r"-?\d+", spec.strip()):
        spec = int(spec)
    if isinstance(spec, str):
        if header is None or spec.lower() not in header:
            raise InputError(f"{table.path}: no column named {spec!r} for {what} (header: {header}; "
                             f"read with {table.layout}).")
        return header.index(spec.lower())
    if isinstance(spec, bool) or not isinstance(spec, (int, np.integer)) or not -ncols <= spec < ncols:
        raise InputError(f"{table.path}: {what} column {spec!r} is not a column index below {ncols} "
                         f"or a name (read with {table.layout}).")
    return int(spec) % ncols


def _numbered(header, prefix) -> list[int]:
    """Indices of the columns ``<prefix>1 .. <prefix>k`` in numeric order (must be contiguous)."""
    found = {int(m.group(1)): i for i, h in enumerate(header) if (m := re.fullmatch(prefix + r"(\d+)", h))}
    return [found[k] for k in sorted(found)] if sorted(found) == list(range(1, len(found) + 1)) else []


def _axes(header, prefix) -> list[int]:
    """Indices of the columns ``<prefix>x``, ``<prefix>y``, ``<prefix>z`` present as a prefix of x, y, z."""
    names = [prefix + a for a in _AXES]
    count = next((k for k, name in enumerate(names) if name not in header), len(names))
    return [header.index(name) for name in names[:count]]


def _time_index(table: _Table, time_column, dt) -> int | None:
    """The time column, or None when ``dt`` gives the time axis."""
    if dt is not None:
        named = [h for h in time_header_names() if table.header and h in table.header]
        if time_column is not None or named:
            which = repr(time_column) if time_column is not None else f"{named[0]!r} in the header"
            raise InputError(f"{table.path}: both dt = {dt:g} and a time column ({which}) are given; "
                             "Try: drop dt to use the file's time stamps, or drop the time column.")
        return None
    if time_column is not None:
        return _column_index(time_column, table, "time")
    if table.header is None:
        return 0
    named = [h for h in time_header_names() if h in table.header]
    if not named:
        raise DemonstrationError(f"{table.path}: no time column: the header {table.header} (read with "
                                 f"{table.layout}) has no column named t, time or timestamp (or t_ms, ...). "
                                 f"Try: {_NO_TIME_HINT}.")
    return table.header.index(named[0])


def _roles(table: _Table, dim, time_column, demo_column, dt, columns):
    """Column indices (time or None, demo id or None, positions, velocities) of a table; with
    ``columns`` the positions are those (other columns ignored, no velocities read); else a header
    column with no role is an InputError (:func:`~.columns.refuse_unclaimed`)."""
    header, ncols = table.header, table.cells.shape[1]
    ti = _time_index(table, time_column, dt)
    if demo_column is None and header and _DEFAULT_DEMO_NAME in header:
        demo_column = _DEFAULT_DEMO_NAME
    di = None if demo_column is None else _column_index(demo_column, table, "demo id")
    if columns is not None:
        pos = [_column_index(c, table, "position") for c in columns]
        if dim is not None and len(pos) != dim:
            raise InputError(f"{table.path}: {len(pos)} position columns {columns} but dim = {dim}.")
        if len(set(pos)) != len(pos):
            raise InputError(f"{table.path}: the position columns {columns} name one column twice. Try: each "
                             "position column once.")
        names = {i: f"{table.header[i]!r}" if table.header else f"column {i}" for i in pos}
        taken = [(i, role) for i, role in ((ti, "time"), (di, "demo id")) if i in pos]
        taken += [(i, "time") for i in pos if table.header and table.header[i] in time_header_names() and i != ti]
        if taken:
            i, role = taken[0]
            others = [h for k, h in enumerate(table.header or []) if k not in (ti, di) and table.header[k] not in time_header_names()]
            raise InputError(f"{table.path}: the position columns include {names[i]}, the {role} column: a model of it "
                             f"would take {role} for a coordinate. Try: only the coordinates' columns, {COLUMNS_HINT}"
                             + (f", e.g. --columns {','.join(suggest_columns(others))}." if others else "."))
        return ti, di, pos, []
    if header is not None:
        pos, vel = _numbered(header, "x") or _axes(header, ""), _numbered(header, "v") or _axes(header, "v")
        if not pos or (vel and len(vel) != len(pos)) or (dim is not None and len(pos) != dim):
            raise DemonstrationError(
                f"{table.path}: header {header} (read with {table.layout}) does not give positions "
                f"x1..xn or x, y, z (and optionally velocities v1..vn or vx, vy, vz with the same "
                f"n{'' if dim is None else f' = {dim}'}). Try: name the position columns, {COLUMNS_HINT}, "
                f"e.g. --columns {','.join(suggest_columns([h for i, h in enumerate(header) if i not in (ti, di)]))}."
            )
        refuse_unclaimed(header, {ti, di, *pos, *vel}, pos, str(table.path))
        return ti, di, pos, vel
    rest = [c for c in range(ncols) if c not in (ti, di)]
    if dim is None or len(rest) == dim:
        return ti, di, rest, []
    if len(rest) == 2 * dim:
        return ti, di, rest[:dim], rest[dim:]
    raise DemonstrationError(
        f"{table.path}: {len(rest)} data columns besides time/demo id (read with {table.layout}), but "
        f"dim = {dim} needs {dim} (positions) or {2 * dim} (positions and velocities)."
    )


def _as_float(table: _Table, columns: list[int]) -> np.ndarray:
    """The numbers in ``columns`` (T, len(columns)); the first cell that is none is named."""
    cells = table.cells[:, columns]
    if table.delimiter == "npy":
        return cells
    text = cells.astype(str)
    if table.decimal == ",":
        text = np.where(np.char.find(text, ".") >= 0, "?", np.char.replace(text, ",", "."))
    try:
        return text.astype(float)
    except ValueError:      # the same rule as _number, which finds the first bad cell
        i, k = next(ik for ik, cell in np.ndenumerate(cells) if _number(cell, table.decimal) is None)
    cell = cells[i, k]
    extra = (" ('.' in a file with decimal commas: thousands separators are not supported)"
             if table.decimal == "," and "." in cell else "")
    raise DemonstrationError(
        f"{table.path}: line {table.lines[i]}, column {columns[k] + 1}: {cell!r} is not a number{extra} "
        f"(read with {table.layout}). Try: fix or remove that line.")


def _demos_from_file(path: Path, dim, time_column, demo_column, dt, time_units, columns):
    """(the file's demonstrations, the names of their position columns: the header's, or None, and per
    demonstration whose time stamps repeat: (source, identical rows dropped, differing rows averaged))."""
    table = _read_table(path)
    ti, di, pos_idx, vel_idx = _roles(table, dim, time_column, demo_column, dt, columns)
    name = None if ti is None or table.header is None else table.header[ti]
    unit = time_unit(name, time_units, str(path))
    times = None if ti is None else _as_float(table, [ti])[:, 0]
    values = _as_float(table, pos_idx + vel_idx)
    n = len(pos_idx)
    cells = table.cells
    ids = np.asarray(cells[:, di]).astype(str) if di is not None else np.zeros(len(cells), dtype=str)
    _, first = np.unique(ids, return_index=True)
    demos, repeats = [], []
    for key in ids[np.sort(first)]:
        rows = ids == key
        source = path.name if di is None else f"{path.name} demo {key}"
        # stamps relative to the first before scaling: exact differences even for epoch stamps
        t = np.arange(np.count_nonzero(rows)) * dt if times is None else (times[rows] - times[rows][0]) * TIME_UNITS[unit]
        t, kept, dropped, averaged = merge_repeated_stamps(t, values[rows])
        if dropped or averaged:
            repeats.append((source, dropped, averaged))
        pos, vel = kept[:, :n], kept[:, n:]
        problem = time_problem(t)
        if problem:
            where = f"time column {table.header[ti]!r}" if table.header else f"column {ti} (time)"
            hint = (f"without a header, column {ti} is time; if the file has no time column give the "
                    "sampling step (--dt STEP, or dt=STEP in load_demos, in s), or add a header row "
                    "such as t,x1,x2"
                    if table.header is None and time_column is None else "fix the time column")
            raise DemonstrationError(f"{source}: {where}: {problem} (read with {table.layout}). "
                                     f"Try: {hint}.")
        if times is not None:
            check_duration(t, unit, source, f"time column {name!r}" if name else f"column {ti}")
        if vel_idx:
            demos.append(Demonstration(t, pos, vel, source))
        else:
            try:
                demos.append(Demonstration.from_positions(t, pos, source))
            except DemonstrationError as exc:
                raise DemonstrationError(f"{source}: {exc}") from exc
    names = None if table.header is None else tuple(table.header[i] for i in pos_idx)
    # names a model file, a plot or generated code could not carry (units_problem's rule) stay unnamed
    return demos, names if names and all(n and not units_problem(n) for n in names) else None, repeats


def repeat_note(repeats: list[tuple[str, int, int]], total: int) -> str:
    """The one-line note of :func:`load_demos` about repeated time stamps (``repeats``: per demonstration
    (source, identical rows dropped, differing rows averaged))."""
    dropped, averaged = sum(r[1] for r in repeats), sum(r[2] for r in repeats)
    return (f"repeated time stamps in {len(repeats)} of {total} demonstrations (first: {repeats[0][0]}): one sample per "
            f"stamp kept, {dropped} identical row(s) dropped and {averaged} differing row(s) averaged into their "
            "stamp's sample.")


def _check_dt(dt) -> float | None:
    if dt is None:
        return None
    real = isinstance(dt, (int, float, np.integer, np.floating)) and not isinstance(dt, bool)
    if not real or not 0 < dt < np.inf:
        raise InputError(f"dt must be a finite number > 0 (the sampling step in s) or None, got {dt!r}.")
    return float(dt)


def load_demos(paths, *, dim: int | None = None, time_column: int | str | None = None,
               demo_column: int | str | None = None, dt: float | None = None, name: str | None = None,
               units: str = "", goal_tol: float | None = None, time_units: str | None = None,
               columns=None) -> Demonstrations | PoseDemonstrations:
    """Load demonstrations from CSV or NPY files and check them (:func:`check_demonstrations`, all but
    the ends: ``goal_tol`` is recorded for the check after preprocessing, which every model's ``fit`` runs).

    Pose files (a header naming quaternion columns qw, qx, qy, qz, e.g. ``t,x,y,z,qw,qx,qy,qz``
    or ``t,x,y,z,qx,qy,qz,qw``) give :class:`~sosdyn.lfd.data.pose.PoseDemonstrations` (read by
    :func:`~sosdyn.lfd.data.pose.load_pose_demos`, for :class:`~sosdyn.PoseCDSP`) unless
    ``columns`` selects positions; then only ``dt``, ``time_units``, ``units`` and ``name`` apply.

    ``paths`` is one path or a sequence of paths. Each file holds one demonstration, except a
    file with a demo-id column, which holds several (split by id, in order of first appearance).
    One row per sample; any dimension n >= 1. Accepted layouts:

    * ``.npy``: a float array T x (1+n) ``[t, x1..xn]`` or T x (1+2n) ``[t, x1..xn, v1..vn]``.
    * ``.csv`` (any text) without header: the same columns; ``demo_column`` (an index) marks a
      demo-id column.
    * ``.csv`` with a header row (a first row none of whose cells is a number): a time column
      named ``t``, ``time`` or ``timestamp`` (any case; ``t_ms``, ``time_us``, ... in that unit),
      positions ``x1..xn`` or ``x, y, z``, optionally velocities ``v1..vn`` or ``vx, vy, vz``
      and a ``demo`` column, in any order. Any other column (Euler angles, joint names, ...; quaternion
      columns make a pose file, above) is an InputError naming it: ``columns`` selects the positions explicitly
      (names like ``["panda_joint1", ..., "panda_joint7"]`` or ``"x,y,z"``, or indices) and
      then the other columns are ignored and velocities are estimated.

    Columns are separated by ',', ';', tab or runs of spaces (detected: ';' or tab when every
    line has one; spaces when every comma sits inside a number; else ','); decimal commas
    ("0,5;1,25") are read when the columns are separated by something else than ','.

    Time: ``dt`` (finite, > 0) says the files have no time column: sample k is at ``k dt``
    (giving dt with a time column is an error). ``time_units`` ("s", "ms" or "us"; default:
    the column name's suffix, else s) is the unit of the time column; times are converted to
    seconds from each demonstration's first stamp (t[0] = 0; epoch stamps keep their precision), and a demonstration lasting more than 10 min is refused as implausible (probably
    ms read as s). Without ``dt`` a header must name a time
    column, and a headerless file has time in column 0 (or ``time_column``); the time must not go
    back, and samples that share a time stamp become one (their mean; identical rows: the row), said
    in one UserWarning for the whole call. ``time_column`` / ``demo_column`` override the defaults (an index, or
    a name with a header). Without a header the non-time columns are positions, unless ``dim``
    is given and they number ``2 * dim``: then the second half are velocities. Files without
    velocities get them from :func:`estimate_velocity`. Blank lines and lines starting with
    ``#`` are skipped. ``name`` defaults to the first file's stem. Errors name the file, the
    line and how it was read (delimiter, decimal mark). The set's ``columns`` are the first file's
    header names of the positions (None without a header, or for names a model file cannot hold).
    """
    paths = [paths] if isinstance(paths, (str, Path)) else list(paths)
    if not paths:
        raise InputError("load_demos needs at least one path.")
    if dim is not None and (isinstance(dim, bool) or not isinstance(dim, (int, np.integer)) or dim < 1):
        raise InputError(f"dim must be a positive integer or None, got {dim!r}.")
    dt = _check_dt(dt)
    time_units, columns = check_time_units(time_units), parse_columns(columns)
    if dt is not None and time_units is not None:
        raise InputError("time_units applies to a time column, dt is in s and says there is none. "
                         "Try: drop one of them.")
    if columns is None and any(map(is_pose_file, paths)):
        return _pose_demos(paths, dim, time_column, demo_column, dt, name, units, goal_tol, time_units)
    demos, names, repeats = [], [], []
    for path in map(Path, paths):
        if path.suffix.lower() not in (".csv", ".npy"):
            raise InputError(f"{path}: unsupported file type {path.suffix!r}; use .csv or .npy.")
        if not path.is_file():
            raise InputError(f"{path}: no such file.")
        found, named, repeated = _demos_from_file(path, dim, time_column, demo_column, dt, time_units, columns)
        demos.extend(found)
        names.append(named)
        repeats.extend(repeated)
    if repeats:
        warnings.warn(repeat_note(repeats, len(demos)), UserWarning, stacklevel=2)
    name = Path(paths[0]).stem if name is None else name
    if columns is not None:
        _refuse_constant(demos, columns)
    return check_demonstrations(Demonstrations(demos, name, units, columns=names[0]), goal_tol=goal_tol, ends=False)


def _refuse_constant(demos: list[Demonstration], columns: list) -> None:
    """InputError when a selected position column holds one value (to round-off) in every sample of
    every demonstration: it carries no motion (a gripper width, a fixed joint)."""
    still = still_coordinates(np.vstack([d.pos for d in demos]))
    if still.any():
        j = int(np.flatnonzero(still)[0])
        moving = [str(c) for c, s in zip(columns, still) if not s]
        raise InputError(f"the position column {columns[j]!r} holds the same value ({demos[0].pos[0, j]:.6g}) in every "
                         "sample of every demonstration: it carries no motion, and a model of it is trivial. Try: "
                         f"leave it out ({COLUMNS_HINT})" + (f", e.g. --columns {','.join(moving)}." if moving else "."))


def _pose_demos(paths, dim, time_column, demo_column, dt, name, units, goal_tol, time_units) -> PoseDemonstrations:
    """:func:`load_demos` of pose files: every file one, and no option that only position files have."""
    plain = [str(p) for p in paths if not is_pose_file(p)]
    if plain:
        raise InputError(f"{plain[0]} has no quaternion columns but other files do: one set of demonstrations is all pose files or all position files. Try: "
                         f"load them separately, or select the position columns ({COLUMNS_HINT}).")
    given = [k for k, v in {"dim": dim if dim != 3 else None, "time_column": time_column, "demo_column": demo_column,
                            "goal_tol": goal_tol}.items() if v is not None]
    if given:
        raise InputError(f"{', '.join(given)} apply to position files; these are pose files (quaternion "
                         "columns; end orientations: PoseCDSP(goal_tol_deg=...)). Try: drop them, or select "
                         f"the position columns ({COLUMNS_HINT}).")
    return load_pose_demos(paths, units, Path(paths[0]).stem if name is None else name, dt, time_units)

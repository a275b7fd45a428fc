"""What the columns of a demonstration file mean: time names and units, explicit position
columns, and the columns no role claims (refused, never dropped silently).

Time: a header column named ``t``, ``time`` or ``timestamp`` holds seconds; with a unit
suffix (``t_ms``, ``time_us``, ``timestamp_s``, ...) it holds that unit. ``time_units``
("s", "ms" or "us") states the unit of a column without suffix; a stated unit that
contradicts the suffix is refused. Times are converted to seconds: t_s = t * TIME_UNITS[unit].
A demonstration longer than :data:`MAX_DEMO_SECONDS` after conversion is refused as
implausible (milliseconds read as seconds make a 5 s reach last 83 min).
"""
from __future__ import annotations

import re

import numpy as np

from sosdyn.errors import DemonstrationError, InputError

TIME_NAMES = ("t", "time", "timestamp")
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
MAX_DEMO_SECONDS = 600.0
#: Names of orientation columns (quaternions, Euler angles, rotation vectors). Files whose header
#: names qw, qx, qy or qz are pose files (:func:`~.pose.is_pose_file`); any other orientation column
#: is refused, naming the quaternion header a pose model reads and the option that selects the positions.
ORIENTATION = re.compile(r"(q|quat|quaternion|orientation|rot|o)_?[wxyz]|roll|pitch|yaw|r[xyz]")
TIME_UNITS_HINT = "--time-units (sosdyn fit / plot) or time_units= (load_demos)"
COLUMNS_HINT = "--columns (sosdyn fit / plot) or columns= (load_demos)"


def time_header_names() -> list[str]:
    """Every header name read as the time column, in order of preference."""
    return [*TIME_NAMES, *(f"{name}_{unit}" for name in TIME_NAMES for unit in TIME_UNITS)]


def check_time_units(time_units) -> str | None:
    """``time_units`` (None, "s", "ms" or "us"), or InputError."""
    if time_units is not None and time_units not in TIME_UNITS:
        raise InputError(f"time_units must be one of {', '.join(TIME_UNITS)} (or None: seconds unless the "
                         f"time column's name says t_ms / t_us), got {time_units!r}.")
    return time_units


def time_unit(column: str | None, time_units: str | None, where: str) -> str:
    """The unit of the time column named ``column`` (None: no header) given ``time_units``."""
    suffix = next((u for u in TIME_UNITS if column and column.endswith("_" + u)
                   and column[:-len(u) - 1] in TIME_NAMES), None)
    if suffix and time_units and time_units != suffix:
        raise InputError(f"{where}: the time column {column!r} says {suffix} but time_units = {time_units!r}. "
                         f"Try: drop the time units ({TIME_UNITS_HINT}) or rename the column.")
    return suffix or time_units or "s"


def check_duration(t: np.ndarray, unit: str, source: str, column: str) -> None:
    """DemonstrationError when the demonstration (times ``t`` in s) lasts longer than
    MAX_DEMO_SECONDS: the time stamps are probably in another unit."""
    duration = float(t[-1] - t[0])
    if duration > MAX_DEMO_SECONDS:
        smaller = [u for u, f in TIME_UNITS.items() if f < TIME_UNITS[unit]]
        try_units = f"the time units {' or '.join(smaller)}" if smaller else "the time column"
        raise DemonstrationError(
            f"{source}: the demonstration lasts {duration:.4g} s ({column} read in {unit}), more than "
            f"{MAX_DEMO_SECONDS / 60:g} min: the time stamps are probably not in {unit}. Try: "
            f"{try_units} ({TIME_UNITS_HINT}, e.g. --time-units ms), or a time column named t_ms.")


def parse_columns(columns) -> list | None:
    """``columns``: None, a comma-separated string of names, or a sequence of names / indices."""
    if columns is None:
        return None
    if isinstance(columns, str):
        columns = [c.strip() for c in columns.split(",")]
    if isinstance(columns, (bytes, dict)) or not hasattr(columns, "__iter__"):
        raise InputError(f"columns must be names like 'x,y,z' or a list of names / indices, got {columns!r}.")
    columns = list(columns)
    if not columns or any(c == "" for c in columns) or len(set(map(str, columns))) != len(columns):
        raise InputError(f"columns must name each position column once, got {columns!r}. Try: e.g. x,y,z "
                         "or panda_joint1,...,panda_joint7.")
    return columns


def suggest_columns(names: list[str]) -> list[str]:
    """The columns a hint proposes as positions among ``names`` (time and demo id already left out):
    the largest family of numbered names sharing a prefix (panda_joint1..panda_joint7, not gripper_width
    beside them), in numeric order; without such a family, the names that are not orientations."""
    families: dict[str, dict[int, str]] = {}
    for name in names:
        m = re.fullmatch(r"(.*?)(\d+)", name)
        if m:
            families.setdefault(m.group(1), {})[int(m.group(2))] = name
    best = max(families.values(), key=len, default={})
    if len(best) >= 2:
        return [best[k] for k in sorted(best)]
    return [h for h in names if not ORIENTATION.fullmatch(h)] or list(names)


def refuse_unclaimed(header: list[str], used: set[int], positions: list[int], where: str) -> None:
    """InputError when header columns besides ``used`` exist: never a silent drop. Orientation
    columns get their own message (the pose header to use); the hint selects the ``positions``."""
    extra = [h for i, h in enumerate(header) if i not in used]
    if not extra:
        return
    positions = ",".join(header[i] for i in positions)
    orientation = [h for h in extra if ORIENTATION.fullmatch(h)]
    if orientation:
        raise InputError(
            f"{where}: orientation columns {orientation} in a position model. Try: for a pose model, "
            f"quaternion columns named qw,qx,qy,qz (a header t,x,y,z,qw,qx,qy,qz: sosdyn fit and load_demos "
            f"then fit / read poses), or select the position columns to ignore them, {COLUMNS_HINT}, e.g. "
            f"--columns {positions or 'x,y,z'}.")
    raise InputError(
        f"{where}: columns {extra} are neither time, demo id, positions nor velocities, and would be "
        f"ignored. Try: select the position columns explicitly, {COLUMNS_HINT}, e.g. --columns "
        f"{positions or ','.join(suggest_columns(extra))}.")

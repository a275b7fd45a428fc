"""What every ``sosdyn`` command shares: the Typer app, the consoles, the global options'
state and small option helpers. The commands live in :mod:`sosdyn.cli` (the package),
:mod:`.fit` and :mod:`.models`."""
from __future__ import annotations

import enum
from contextlib import nullcontext
from typing import Annotated

import numpy as np
import typer
from rich.console import Console

from ..errors import InputError
from ..lfd.data.columns import TIME_UNITS

app = typer.Typer(name="sosdyn", no_args_is_help=True, add_completion=False,
                  help="SOS programming and provably convergent motion learning (CDSP).")
lasa_app = typer.Typer(no_args_is_help=True, help="The LASA handwriting data set.")
app.add_typer(lasa_app, name="lasa")

out = Console()
err = Console(stderr=True)


class State:
    """Global options, set by the app callback."""

    quiet = False
    debug = False


def info(message: str) -> None:
    """A summary line on stdout, never wrapped (nothing when --quiet)."""
    if not State.quiet:
        out.print(message, soft_wrap=True)


def status(message: str):
    """A spinner while a long single call runs (nothing when --quiet)."""
    return nullcontext() if State.quiet else err.status(message)


def positive(value: float | None) -> float | None:
    """Option callback: a finite number > 0 (or not given)."""
    if value is not None and not 0 < value < float("inf"):
        raise typer.BadParameter(f"must be a finite number > 0, got {value}.")
    return value


TimeUnit = enum.Enum("TimeUnit", {u: u for u in TIME_UNITS}, type=str)

#: ``--time-units`` and ``--columns`` of the commands that read demonstration files (fit, plot).
TimeUnitsOption = Annotated[TimeUnit | None, typer.Option(
    "--time-units", help="Unit of the files' time column (converted to s); default: s, or the column "
                         "name's suffix (t_ms, time_us).", show_default=False)]
ColumnsOption = Annotated[str | None, typer.Option(
    "--columns", help="The position columns, comma-separated names (or indices), e.g. x,y,z or "
                      "panda_joint1,...,panda_joint7; other columns are then ignored.",
    show_default="x1..xn or x,y,z; any other column is refused")]


def read_options(dt, time_units, columns) -> dict:
    """The ``load_demos`` keywords of the file-reading options that were given."""
    given = {"dt": dt, "time_units": time_units and time_units.value, "columns": columns}
    return {k: v for k, v in given.items() if v is not None}


def parse_point(text: str, option: str = "--start") -> np.ndarray:
    """``"10,-5"`` as the array [10, -5]; InputError naming ``option`` unless finite numbers."""
    try:
        point = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"{option} expects comma-separated numbers like 10,-5; got {text!r}. "
                         "Try: one number per dimension, no spaces or brackets.") from None
    if not np.all(np.isfinite(point)):
        raise InputError(f"{option} must be finite; got {text!r}. Try: finite numbers.")
    return point

"""``sosdyn fit``: demonstrations in, a certified model file out, of the family that fits them
(:func:`~sosdyn.lfd.model.base.family_for`: pose CSVs give the pose model, ``--order 2`` the
second-order model, else the first-order CDSP); everything after the choice goes through the model
interface (:class:`~sosdyn.lfd.model.base.MotionModel`), never asking which family it holds.

Inputs: files, folders (their ``*.csv`` / ``*.npy``), quoted patterns (``'demos/*.csv'``),
``lasa:NAME`` or ``dataset:NAME`` (a shipped real set, :func:`sosdyn.load_dataset`); read by
:func:`sosdyn.load_demos` (headers ``t,x,y[,z]``, ``t,x1..xn``, optional velocities, or no header
with time in column 0; pose CSVs ``t,x,y,z,qw,qx,qy,qz`` or ``...,qx,qy,qz,qw`` give a pose model;
``--dt`` for files without time, ``--time-units ms`` or a ``t_ms`` column
for millisecond stamps, ``--columns`` to name the position columns, e.g. joint names; a column
with no role is refused, never dropped).
``--units`` is recorded, not applied: it names the units of the positions in the model file
(``state.units_``), on plot axes and in exported code; the numbers are used as they are.
Before the fit the demonstrations are prepared by the family (``--smooth``, ``--trim-rest``,
``--align-ends``: the model's ``prepare``; pose demonstrations take none) and crossings are
reported when the family cannot follow them. An option the family has no parameter for is refused,
naming the family that takes it; an option whose parameter applies only with another's value
(``only_with``: the second-order mixture's --components, --max-iter, --solver-method) is refused
without it, naming the option to add. Progress: one plain line per
convex step on stdout (step, cost, seconds of the step and since the start) when stdout is not a
terminal, a live status line when it is; nothing with ``--quiet``. After the fit: the
certificate, right under it a caution when reproductions do not reach the goal within twice their
demonstration's duration (what the certificate does and does not promise), the model's summary (e.g.
which warp candidate was kept), a line for every fit that stopped at the iteration cap, and a table of
how the model reproduces each demonstration (with the time each takes to reach the goal).
"""
from __future__ import annotations

import enum
import math
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..errors import InputError
from ..lfd.model.cdsp import DEFAULTS
from ..lfd.data.demonstrations import GOAL_TOL_FRACTION, units_problem
from ..lfd.data.pose import GOAL_TOL_DEG
from ..lfd.fit.params import FLOORS, GATINGS, MAX_CORRECTIVE_ROUNDS, METHODS, PRESETS, WARPS
from ..lfd.fit.second_order import METHODS as SECOND_ORDER_METHODS
from ..lfd.fit.second_order.params import FIELDS as SECOND_ORDER_FIELDS
from ..lfd.model.base import FAMILIES, family_for
from .base import ColumnsOption, State, TimeUnitsOption, app, err, info, out, positive, read_options
from .fitdata import DATASET_PREFIX, load_dataset_input, parse_align, parse_smooth, prepare, print_arrival, print_score
from .paths import LASA_PREFIX, check_folder, check_output, demo_inputs

Preset = enum.Enum("Preset", {name: name for name in PRESETS}, type=str)


SolverMethod = enum.Enum("SolverMethod", {m: m for m in dict.fromkeys(METHODS + SECOND_ORDER_METHODS)}, type=str)
Warp = enum.Enum("Warp", {name: name for name in WARPS}, type=str)
Gating = enum.Enum("Gating", {name: name for name in GATINGS}, type=str)
SecondOrderField = enum.Enum("SecondOrderField", {name: name for name in SECOND_ORDER_FIELDS}, type=str)

#: The model parameter each fit option sets (an option whose parameter the family lacks is refused).
OPTIONS = {"n_components": "--components", "metric_degree": "--metric-degree", "field_degree": "--field-degree",
           "gamma": "--gamma", "solver": "--solver", "solver_method": "--solver-method", "random_state": "--seed",
           "corrective_rounds": "--corrective-rounds", "warp": "--warp", "max_iter": "--max-iter",
           "gating": "--gating", "speed_floor": "--speed-floor", "goal_tol_deg": "--goal-tol-deg", "field": "--field"}


class Switch(str, enum.Enum):
    on = "on"
    off = "off"


def progress_line(row: dict, step_s: float, total_s: float) -> str:
    """One convex step of a fit: ``step 3 (metric): cost 12.5 (0.21 s; 1.4 s since start)``,
    prefixed by ``warp 60 maps, decay 1, `` for a candidate of warp="auto" and ``corrective
    round 1, `` during a refit on corrective data. ``step_s``: since the previous line."""
    head = (f"{row['block']} block, " if row.get("block") else "") + \
        (f"warp {row['warp']}, " if row.get("warp") else "") + \
        (f"corrective round {row['round']}, " if row.get("round") else "")
    return (f"{head}step {row['iteration'] + 1} ({row['step']}): cost {row['cost']:.6g} "
            f"({step_s:.2f} s; {total_s:.1f} s since start)")


class FitProgress:
    """Shows a fit's steps: plain lines on stdout when it is not a terminal (pipes, logs, CI),
    a live status line on a terminal; nothing when --quiet. Use as a context manager and pass
    :meth:`row` as the model's ``progress``; ``rows`` keeps every row by (warp, round)."""

    def __init__(self, message: str):
        self.message, self.start, self._status = message, time.perf_counter(), None
        self._last = self.start
        self.rows: dict[tuple, list[dict]] = {}

    def __enter__(self):
        if not State.quiet and out.is_terminal:
            self._status = err.status(self.message + " ...")
            self._status.__enter__()
        elif not State.quiet:
            out.print(self.message, highlight=False, soft_wrap=True)
        return self

    def __exit__(self, *exc):
        if self._status is not None:
            self._status.__exit__(*exc)
        return False

    def row(self, row: dict) -> None:
        now = time.perf_counter()
        line = progress_line(row, now - self._last, now - self.start)
        self._last = now
        self.rows.setdefault((row.get("block"), row.get("warp"), row.get("round")), []).append(row)
        if self._status is not None:
            self._status.update(f"{self.message}: {line}")
        elif not State.quiet:
            out.print(line, highlight=False, soft_wrap=True)

    def caps(self, model) -> list[str]:
        """One line per fit (candidate / round) that hit the iteration cap (``model.iteration_cap``)."""
        lines = []
        for (block, warp, round_), rows in self.rows.items():
            cap = model.iteration_cap(rows)
            if cap:
                who = " ".join(filter(None, (block and f"{block} block", warp and f"warp {warp}",
                                             round_ and f"corrective round {round_}")))
                lines.append(f"{who or 'the fit'}: {cap} (more iterations: --max-iter)")
        return lines


def check_options(family, given: dict) -> None:
    """InputError naming the options (:data:`OPTIONS`) whose parameter ``family`` does not have, and
    the families that have it; or an option whose parameter applies only when another has a value
    (``family.only_with``) given without it, naming the option that sets it."""
    params = family().get_params()
    bad = [name for name in given if name not in params]
    if bad:
        owners = sorted({cls.__name__ for cls in FAMILIES.values() for name in bad if name in cls().get_params()})
        listed = ", ".join(OPTIONS[name] for name in bad)
        raise InputError(f"{listed} {'does' if len(bad) == 1 else 'do'} not apply to a {family.__name__} model"
                         f"{' (' + ' and '.join(owners) + ' take' + ('s' if len(owners) == 1 else '') + ' it)' if owners else ''}"
                         f". Try: drop {'it' if len(bad) == 1 else 'them'}.")
    for name in given:
        other, value = family.only_with.get(name, (None, None))
        if other is not None and given.get(other, params[other]) != value:
            now = f"{OPTIONS[other]} {given[other]}" if other in given else f"the default {OPTIONS[other]} {params[other]}"
            raise InputError(f"{OPTIONS[name]} applies to a {family.__name__} model with {OPTIONS[other]} {value} "
                             f"only, not with {now}. Try: add {OPTIONS[other]} {value}, or drop {OPTIONS[name]}.")


def _units(value: str | None) -> str | None:
    """Option callback: a units' name (:func:`~sosdyn.lfd.data.demonstrations.units_problem`)."""
    problem = None if value is None else units_problem(value)
    if problem:
        raise typer.BadParameter(f"{problem}, e.g. m or mm.")
    return value


def open_degrees(value: float | None) -> float | None:
    """``--goal-tol-deg`` callback: a number strictly between 0 and 180 (or not given)."""
    if value is not None and not 0 < value < 180:
        raise typer.BadParameter(f"must be a number of degrees in (0, 180), both ends excluded; got {value}.")
    return value


def _default(name: str) -> str:
    return f"{DEFAULTS[name]}, or the preset's"


def parse_floor(value: str | None) -> str | float | None:
    """``--speed-floor``: auto, none, or a rate > 0 (1/s)."""
    if value is None or value in FLOORS:
        return value
    try:
        rate = float(value)
    except ValueError:
        raise typer.BadParameter(f"must be auto, none or a rate > 0 (1/s), got {value!r}.") from None
    if not (math.isfinite(rate) and rate > 0):
        raise typer.BadParameter(f"the rate must be a finite number > 0 (1/s), got {value!r}.")
    return rate


@app.command()
def fit(
    demos: Annotated[list[str], typer.Argument(
        help="Demonstration files (CSV/NPY, one demonstration each, or several with a demo column), "
             "folders of them, quoted patterns like 'demos/*.csv', or one lasa:NAME or dataset:NAME alone.",
        show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="Where to save the model (JSON).")] = Path("model.json"),
    order: Annotated[int, typer.Option(
        "--order", min=1, max=2, help="1: a first-order model xdot = f(x) (CDSP; PoseCDSP for pose files); 2: a "
                                      "second-order model xddot = a(x, xdot) (SecondOrderCDSP), which can follow "
                                      "demonstrations that cross.")] = 1,
    preset: Annotated[Preset | None, typer.Option(
        help="Named parameter set (see CDSP.preset); options given here override it.",
        show_default="none: CDSP()'s defaults")] = None,
    components: Annotated[int | None, typer.Option("--components", "-k", min=1, help="Gaussian components K.",
                                                   show_default=_default("n_components"))] = None,
    metric_degree: Annotated[int | None, typer.Option(min=0, help="Degree of the polynomial metric M(z) (even).",
                                                      show_default=_default("metric_degree"))] = None,
    field_degree: Annotated[int | None, typer.Option(min=1, help="Degree of the polynomial fields f_k (odd).",
                                                     show_default=_default("field_degree"))] = None,
    gamma: Annotated[float | None, typer.Option(callback=positive, help="Contraction rate (1/s, > 0).",
                                                show_default=_default("gamma"))] = None,
    solver: Annotated[str | None, typer.Option(help="Conic solver, e.g. CLARABEL or SCS.",
                                               show_default=str(DEFAULTS["solver"]))] = None,
    solver_method: Annotated[SolverMethod | None, typer.Option(
        "--solver-method", "--method", help="How the bilinear program is solved: ica (joint convex steps) or "
                                            "alternating; a second-order mixture (--field mixture) also energy.",
        show_default=_default("solver_method"))] = None,
    corrective_rounds: Annotated[int | None, typer.Option(
        min=0, max=MAX_CORRECTIVE_ROUNDS, help="Refits on corrective data from the model's own rollouts of the demonstrations (0 = plain "
                    "fit; each round is a whole fit).", show_default=_default("corrective_rounds"))] = None,
    warp: Annotated[Warp | None, typer.Option(
        help="Fit through a diffeomorphic pre-warp: auto = fit without and with each candidate warp, keep "
             "the one that reproduces the demonstrations best; none = no warp.",
        show_default=_default("warp"))] = None,
    seed: Annotated[int | None, typer.Option(min=0, max=2**32 - 1, help="Random seed (EM initialisation).",
                                             show_default=str(DEFAULTS["random_state"]))] = None,
    max_iter: Annotated[int | None, typer.Option(
        "--max-iter", min=0, help="Iteration cap of the alternation (each fit, candidate or round).",
        show_default=f"{DEFAULTS['max_iter']}, or the preset's (second order: 50)")] = None,
    gating: Annotated[Gating | None, typer.Option(
        help="The mixture weights h_k: posterior; tempered (the posterior at the data, turning smoothly off it); "
             "smooth (the posterior at the data, fading to constant weights far off it: the smoothest motions away "
             "from the demonstrations).", show_default=_default("gating"))] = None,
    speed_floor: Annotated[str | None, typer.Option(
        "--speed-floor", callback=parse_floor, metavar="auto|none|RATE",
        help="A time change of the field (same paths, same certificate): at least RATE (1/s) x the distance to the "
             "goal, at most 10x the field's speed; auto = the least that makes the reproductions of the "
             "demonstrations arrive within 1.5x their duration (none if they do).",
        show_default=_default("speed_floor"))] = None,
    dt: Annotated[float | None, typer.Option(
        callback=positive, help="Sampling step (s) of files without a time column: sample k is at k*dt.",
        show_default="none: the files' time column")] = None,
    units: Annotated[str | None, typer.Option(
        callback=_units, help="Units of the positions, e.g. m or mm: recorded in the model file, shown on "
                              "plots; the numbers are not rescaled.", show_default="none")] = None,
    goal_tol: Annotated[float | None, typer.Option(
        "--goal-tol", min=0.0, help="Largest distance of a demonstration's end point from the mean end point "
                                    "(data units) after preprocessing (--align-ends moves the ends onto their "
                                    "mean); demonstrations ending farther apart are refused, as by Python's fit.",
        show_default=f"{GOAL_TOL_FRACTION:.0%} of the data's bounding-box diagonal")] = None,
    smooth: Annotated[str, typer.Option(
        parser=parse_smooth, help="Savitzky-Golay smoothing before differentiation: auto = a window from the "
                                  "noise and the sampling (off for smooth data such as LASA), off, or an odd "
                                  "window in samples.")] = "auto",
    trim_rest: Annotated[Switch, typer.Option(
        "--trim-rest", help="Drop the resting samples at the start and end of each demonstration "
                            "(within 5 noise sigmas of the first / last sample).")] = Switch.on,
    align_ends: Annotated[str, typer.Option(
        "--align-ends", parser=parse_align,
        help="Blend each demonstration onto the mean end point over its last half and print the shifts: auto = "
             "when the ends spread more than 1% of the data's diagonal; on; off; or a number = on, accepting "
             "shifts up to it (data units; default limit 25% of the diagonal).")] = "auto",
    goal_tol_deg: Annotated[float | None, typer.Option(
        "--goal-tol-deg", callback=open_degrees, help="Pose files: refuse end orientations farther than this (deg, "
                                                      "strictly between 0 and 180) from their chordal mean; nearer "
                                                      "ones are aligned to it.", show_default=f"{GOAL_TOL_DEG:g}")] = None,
    field: Annotated[SecondOrderField | None, typer.Option(
        "--field", help="Second order: tracking = the demonstrations tracked in (x, v), certified by an energy "
                        "tank; mixture = a mixture of linear fields under one quadratic certificate.",
        show_default="tracking")] = None,
    time_units: TimeUnitsOption = None,
    columns: ColumnsOption = None,
) -> None:
    """Learn a certified model from demonstrations and save it.

    Pose CSVs (a header t,x,y,z,qw,qx,qy,qz or t,x,y,z,qx,qy,qz,qw) give a pose model (PoseCDSP:
    position and orientation), unless --columns selects positions; --order 2 gives a second-order
    model (SecondOrderCDSP). Options left out use the model's defaults (shown: CDSP()'s), or the preset's.
    """
    import sosdyn as sd

    lasa = len(demos) == 1 and demos[0].startswith(LASA_PREFIX)
    shipped = len(demos) == 1 and demos[0].startswith(DATASET_PREFIX)
    if lasa and (dt, units, goal_tol, time_units, columns) != (None,) * 5:
        raise InputError("--dt, --units, --goal-tol, --time-units and --columns apply to files, not to "
                         "lasa:NAME (time in s, positions in mm). Try: drop them.")
    if shipped and (units, time_units, columns) != (None,) * 3:
        raise InputError("--units, --time-units and --columns apply to files; a shipped data set names its own "
                         "units and columns. Try: drop them.")
    paths = [] if lasa or shipped else demo_inputs(demos)
    check_output(out_path, paths, "demonstration file")
    check_folder(out_path.parent)
    folder = len(demos) == 1 and Path(demos[0]).is_dir()      # the set is named after its folder
    read = {"units": units, "goal_tol": goal_tol, "name": Path(demos[0]).resolve().name if folder else None}
    if shipped:
        data = load_dataset_input(demos[0], dt)
    else:
        data = sd.load_lasa(demos[0].removeprefix(LASA_PREFIX)) if lasa else sd.load_demos(
            paths, **{k: v for k, v in read.items() if v is not None},   # the ends: checked after prepare
            **read_options(dt, time_units, columns))
    family = family_for(data, order)
    options = {"n_components": components, "metric_degree": metric_degree, "field_degree": field_degree,
               "gamma": gamma, "solver": solver, "solver_method": solver_method and solver_method.value,
               "random_state": seed, "corrective_rounds": corrective_rounds, "warp": warp and warp.value,
               "max_iter": max_iter, "gating": gating and gating.value, "speed_floor": speed_floor,
               "goal_tol_deg": goal_tol_deg, "field": field and field.value}
    given = {k: v for k, v in options.items() if v is not None}
    check_options(family, given)
    data = prepare(family, data, smooth, trim_rest is Switch.on, align_ends)
    model = family.preset(preset.value, **given) if preset else family(**given)
    with FitProgress(f"fitting {family.__name__} to {len(data)} demonstrations of {data.name}") as progress:
        model.progress = progress.row
        model.fit(data)
    model.progress = None
    model.save(out_path)
    info(f"[green]saved[/] {escape(str(out_path))}  ({len(data)} demonstrations, fit in "
         f"{time.perf_counter() - progress.start:.1f} s, {len(model.history_)} convex steps)")
    lines = model.summary()
    rows = None if State.quiet else model.score(data)
    info(f"certificate: {'[green]passed[/]' if model.certified_ else '[red]FAILED[/]'} — {escape(lines[0])}")
    params = model.get_params()
    print_arrival(rows, params.get("gamma"))
    for line in lines[1:]:
        info(escape(line))
    for line in progress.caps(model):
        info(f"[yellow]iteration cap[/]: {escape(line)}")
    print_score(rows, data)

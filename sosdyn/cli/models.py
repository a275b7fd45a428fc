"""The commands on a saved model of any family: ``sosdyn rollout``, ``sosdyn export`` and ``sosdyn plot``,
each through the model interface (:class:`~sosdyn.lfd.model.base.MotionModel`: its ``layout``,
``rollout``, ``export`` and ``reproductions``), never asking which family the file holds. An option
only some families take (``--start-velocity``: second order; ``--max-angular-speed``: poses) is
refused for the others, naming who takes it."""
from __future__ import annotations

import enum
import inspect
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from ..errors import InputError
from ..lfd.model.base import FAMILIES
from .base import ColumnsOption, TimeUnitsOption, app, info, out, parse_point, positive, read_options, status
from .fitdata import DATASET_PREFIX, load_dataset_input
from .paths import check_folder, check_output, demo_inputs, existing


def _events(specs: list[str] | None, option: str, example: str) -> list[tuple[float, np.ndarray]]:
    """``["T:V1,V2", ...]`` as [(T, vector)]; InputError naming ``option`` otherwise."""
    events = []
    for spec in specs or []:
        when, sep, vector = spec.partition(":")
        try:
            time = float(when) if sep else None
        except ValueError:
            time = None
        if time is None:
            raise InputError(f"{option} expects TIME:VECTOR like {example}; got {spec!r}. Try: the time "
                             "in s, a colon, then comma-separated numbers.")
        events.append((time, parse_point(vector, option)))
    return events


def _dimension(point: np.ndarray, names: tuple[str, ...], option: str) -> np.ndarray:
    """``point`` if it has one number per name; else InputError naming them."""
    if point.shape != (len(names),):
        example = ",".join("1" if name == "qw" else "0" for name in names)     # a quaternion's w: a valid pose
        raise InputError(f"{option} has {point.size} numbers but the model takes {len(names)}: {','.join(names)}. "
                         f"Try: {len(names)} comma-separated numbers, e.g. {example}.")
    return point


def family_keywords(model, method: str, given: dict) -> dict:
    """The keywords ``{name: (option, value)}`` given on the command line that ``model.method`` takes
    (value not None), as ``{name: value}``; InputError naming an option it does not take and the
    families whose ``method`` does."""
    takes = inspect.signature(getattr(model, method)).parameters
    for name, (option, value) in given.items():
        if value is not None and name not in takes:
            owners = [cls.__name__ for cls in FAMILIES.values() if name in inspect.signature(getattr(cls, method)).parameters]
            raise InputError(f"{option} does not apply to a {type(model).__name__} model ({' and '.join(owners)} "
                             "takes it). Try: drop it.")
    return {name: value for name, (_, value) in given.items() if value is not None}


MaxAngularSpeedOption = Annotated[float | None, typer.Option(
    "--max-angular-speed", callback=positive, help="Pose models: largest angular speed |omega| (rad/s); v and omega "
                                                   "are scaled by one factor (same path and goal).", show_default="none")]


@app.command()
def rollout(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit`.", show_default=False)],
    start: Annotated[str, typer.Option("--start", "--from", help="Start state, comma-separated, e.g. 10,-5.",
                                       show_default=False)],
    duration: Annotated[float, typer.Option(callback=positive, help="Seconds to integrate.")] = 10.0,
    dt: Annotated[float | None, typer.Option(callback=positive, help="Time step (s); default: the model's.")] = None,
    push: Annotated[list[str] | None, typer.Option(
        "--push", help="A push at time T: the state jumps by DX,DY[,DZ], e.g. 2:5,0; repeat for several.",
        show_default=False)] = None,
    goal_change: Annotated[list[str] | None, typer.Option(
        "--goal-change", help="From time T on the goal is X,Y[,Z], e.g. 3:10,5; repeat for several.",
        show_default=False)] = None,
    max_speed: Annotated[float | None, typer.Option(
        "--max-speed", callback=positive, help="Largest speed (units/s): the velocity is scaled down, same "
                                               "direction and path.", show_default="none")] = None,
    max_angular_speed: MaxAngularSpeedOption = None,
    start_velocity: Annotated[str | None, typer.Option(
        "--start-velocity", help="Second-order models: the start velocity, comma-separated (units/s).",
        show_default="0: at rest")] = None,
    out_path: Annotated[Path | None, typer.Option("--out", "-o", help="Write t and the states as CSV.")] = None,
) -> None:
    """Integrate a saved model from a start state and print the end point.

    Pushes and goal changes happen at the given times; with --out also write the trajectory
    as CSV (columns t and the model's columns: loadable again as a demonstration). A pose model starts
    from x,y,z,qw,qx,qy,qz, is pushed by dx,dy,dz,wx,wy,wz (a world rotation vector), takes goal poses,
    and writes t,x,y,z,qw,qx,qy,qz. A second-order model starts at rest unless --start-velocity, and
    a push may also change the velocity (DX..,DV..)."""
    import sosdyn as sd

    x0 = parse_point(start, "--start")
    v0 = None if start_velocity is None else parse_point(start_velocity, "--start-velocity")
    pushes, goals = _events(push, "--push", "2:5,0"), _events(goal_change, "--goal-change", "3:10,5")
    existing(model_path, "model file")
    if out_path is not None:
        check_output(out_path, [model_path], "model file")
        check_folder(out_path.parent)
    model = sd.load_model(model_path)
    extra = family_keywords(model, "rollout", {"max_angular_speed": ("--max-angular-speed", max_angular_speed),
                                               "v0": ("--start-velocity", v0)})
    layout = model.layout()
    x0 = _dimension(x0, layout.start, "--start")
    for option, events, accepted in (("--push", pushes, layout.pushes), ("--goal-change", goals, (layout.goal,))):
        for when, vector in events:
            if not any(vector.shape == (len(names),) for names in accepted):
                _dimension(vector, accepted[0] if len(accepted) == 1 else accepted[-1], option)
            if not 0 <= when <= duration:
                raise InputError(f"{option} time {when:g} is outside [0, --duration {duration:g}]. Try: a "
                                 "time within the rollout, or a longer --duration.")
    step = {} if dt is None else {"dt": dt}
    traj = model.rollout(x0, duration, perturbations=pushes, goal_changes=goals, max_speed=max_speed, **extra, **step)
    t, states = np.asarray(traj.t), np.asarray(traj.states)
    if out_path is not None:                     # the layout load_demos reads
        np.savetxt(out_path, np.column_stack([t, states]), delimiter=",", comments="",
                   header=",".join(["t", *layout.columns]),
                   fmt="%.9g")                # 9 significant digits: readable, and well below any sensor's noise
        info(f"[green]wrote[/] {escape(str(out_path))}  ({len(t)} steps)")
    end = ", ".join(f"{v:.4g}" for v in states[-1])
    goal = ", ".join(f"{v:.4g}" for v in traj.goal_history[-1])
    out.print(f"t = {t[-1]:.3g} s: x = ({end}), goal ({goal})")


class ExportTarget(str, enum.Enum):
    python = "python"
    cpp = "cpp"


@app.command("export")
def export_model(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit`.", show_default=False)],
    target: Annotated[ExportTarget, typer.Option("--to", help="python: one numpy-only module; cpp: a "
                                                "header-only C++17 evaluator.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The file to write (.py or .hpp).",
                                           show_default=False)],
    max_speed: Annotated[float | None, typer.Option(
        "--max-speed", callback=positive, help="Largest speed (units/s) of the exported field: the velocity is "
                                               "scaled down, same direction, path and goal.", show_default="none")] = None,
    max_angular_speed: MaxAngularSpeedOption = None,
    namespace: Annotated[str | None, typer.Option(
        "--namespace", help="--to cpp: the C++ namespace of the evaluator (a C++ identifier, not a keyword).",
        show_default="the model's: cdsp_model, pose_model or second_order_model")] = None,
) -> None:
    """Write a standalone evaluator of a saved model (Python + numpy, or C++17).

    No sosdyn is needed to run it: Python `predict(X, goal=None) -> Xdot` with numpy only, or
    C++17 `bool predict(const double* x, double* xdot, const double* goal = nullptr)`; the goal
    can move at run time. A pose model adds `predict_pose(x, quat, goal=None) -> (v, omega)`
    (Python: numpy + scipy) or `pose_model_pose::predict_pose(x, quat, v, omega, goal)` (C++); a
    second-order model gives `acceleration(X, V, goal=None)` or
    `second_order_model::acceleration(x, v, a, goal)` (C++). --namespace renames the C++ namespace."""
    import sosdyn as sd

    from ..lfd.model.fileformat import replace_atomically

    if namespace is not None and target is not ExportTarget.cpp:
        raise InputError("--namespace names the C++ namespace; a Python module has none. Try: drop it, or --to cpp.")
    existing(model_path, "model file")
    check_output(out_path, [model_path], "model file")
    check_folder(out_path.parent)
    model = sd.load_model(model_path)
    method = "to_python" if target.value == "python" else "to_cpp"
    extra = family_keywords(model, method, {"max_angular_speed": ("--max-angular-speed", max_angular_speed)})
    source = model.export(target.value, max_speed=max_speed, **extra,
                          **({} if namespace is None else {"namespace": namespace}))
    replace_atomically(out_path, source.encode("utf-8"))
    info(f"[green]wrote[/] {escape(str(out_path))}  ({target.value}, {len(source.splitlines())} lines)")


PLOT_FORMATS = (".png", ".svg")


def _model_and_demos(inputs: list[str], demos: list[str] | None) -> tuple[Path, list[str]]:
    """``sosdyn plot MODEL --demos a.csv b.csv``: the shell words after ``--demos`` that are not
    the option's own value arrive as extra arguments; they are demonstrations when ``--demos`` is
    given. The model is the one ``.json`` among the words (else the first)."""
    jsons = [w for w in inputs if w.lower().endswith(".json")]
    model = jsons[0] if len(jsons) == 1 else inputs[0]
    rest = [w for w in inputs if w is not model]
    if rest and not demos:
        raise InputError(f"unexpected arguments {rest} after the model {model}. Try: --demos {' '.join(rest)} "
                         "to draw them as demonstrations.")
    return Path(model), [*(demos or []), *rest]


@app.command()
def plot(
    inputs: Annotated[list[str], typer.Argument(
        help="A model saved by `sosdyn fit` (and, after --demos, more demonstration files).",
        metavar="MODEL", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The figure (.png or .svg).", show_default=False)],
    demos: Annotated[list[str] | None, typer.Option(
        "--demos", help="Demonstrations to draw: CSV/NPY files (--demos a.csv b.csv), folders, quoted patterns "
                        "('demos/*.csv'), lasa:NAME or dataset:NAME, as `sosdyn fit` takes them. Reproductions start from "
                        "their first states.", show_default=False)] = None,
    duration: Annotated[float | None, typer.Option(callback=positive, help="Seconds per reproduction; "
                                                   "default: twice its demonstration's duration (10 s without).")] = None,
    dt: Annotated[float | None, typer.Option(
        callback=positive, help="Sampling step (s) of demonstration files without a time column.",
        show_default="none: the files' time column")] = None,
    time_units: TimeUnitsOption = None,
    columns: ColumnsOption = None,
) -> None:
    """Plot a saved model of any family: streamlines, 3-D trajectories, time series or pose paths.

    Streamlines of a first-order field for n = 2 (a second-order model: its paths), 3-D trajectories
    with their projections on the box's walls for n = 3, each dimension of the reproductions over
    time for n > 3; axes named by the model's columns and units. The demonstrations are read with the
    model's columns unless --columns. Without --demos the reproductions start at the mixture's means.
    A pose model needs --demos (pose CSVs): 3-D paths with orientation frames."""
    import matplotlib as mpl

    import sosdyn as sd

    from ..report.figures import STYLE, model_figure

    model_path, demos = _model_and_demos(inputs, demos)
    if out_path.suffix.lower() not in PLOT_FORMATS:
        raise InputError(f"--out {out_path} must end in .png or .svg. Try: --out {out_path.with_suffix('.png')}.")
    lasa = len(demos) == 1 and demos[0].startswith("lasa:")
    shipped = len(demos) == 1 and demos[0].startswith(DATASET_PREFIX)
    paths = [] if lasa or shipped else demo_inputs(demos)
    existing(model_path, "model file")
    check_output(out_path, [model_path, *paths], "input")
    check_folder(out_path.parent)
    model = sd.load_model(model_path)
    if columns is None and model.columns_ is not None:      # the position columns the model was fitted to
        columns = ",".join(model.columns_)
    data = None if not demos else sd.load_lasa(demos[0].removeprefix("lasa:")) if lasa else \
        load_dataset_input(demos[0], dt) if shipped else sd.load_demos(paths, **read_options(dt, time_units, columns))
    dim = len(model.names())
    if data is not None and data[0].pos.shape[1] != dim:
        raise InputError(f"the demonstrations are {data[0].pos.shape[1]}-D but the model is {dim}-D. "
                         "Try: the demonstrations the model was fitted to.")
    with status("rolling out reproductions ..."):
        view = model.reproductions(data, duration)
    with mpl.rc_context(STYLE):
        model_figure(view, model_path.stem).savefig(out_path, format=out_path.suffix.lower()[1:], dpi=150,
                                                    metadata=_no_date(out_path))
    info(f"[green]wrote[/] {escape(str(out_path))}  ({dim}-D {type(model).__name__} model, {len(view.runs)} "
         f"reproductions{' of ' + str(len(view.demos)) + ' demonstrations' if view.demos else ''})")


def _no_date(path: Path) -> dict:
    """savefig metadata: no creation date in an SVG, so equal inputs give equal files."""
    return {"Date": None} if path.suffix.lower() == ".svg" else {}

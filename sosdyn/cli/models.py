"""The commands on a saved model: ``sosdyn rollout``, ``sosdyn export`` and ``sosdyn plot``; a pose
model file (``sosdyn-pose``) is exported and drawn by :mod:`.poses`."""
from __future__ import annotations

import enum
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from ..errors import InputError
from ..lfd.model.pose import PoseCDSP
from .base import ColumnsOption, TimeUnitsOption, app, info, out, parse_point, positive, read_options, status
from .paths import check_folder, check_output, demo_inputs, existing
from .poses import POSE_HEADER, POSE_SIZES, MaxAngularSpeedOption, check_angular, export_pose, plot_pose


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


def _dimension(point: np.ndarray, dim: int, option: str, layout: str | None = None,
               example: str | None = None) -> np.ndarray:
    """``point`` if it has ``dim`` numbers; else InputError (``layout`` and ``example``: what they are
    and a valid value, for a pose model)."""
    if point.shape != (dim,):
        what = f"the model is {dim}-D" if layout is None else f"a pose model takes {dim}: {layout}"
        raise InputError(f"{option} has {point.size} numbers but {what}. Try: {dim} "
                         f"comma-separated numbers, e.g. {example or ','.join(['0'] * dim)}.")
    return point


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
    out_path: Annotated[Path | None, typer.Option("--out", "-o", help="Write t and positions as CSV.")] = None,
) -> None:
    """Integrate a saved model from a start state and print the end point.

    Pushes and goal changes happen at the given times; with --out also write the trajectory
    as CSV (columns t,x1..xn: loadable again as a demonstration). A pose model starts from
    x,y,z,qw,qx,qy,qz, is pushed by dx,dy,dz,wx,wy,wz (a world rotation vector), takes goal poses,
    and writes t,x,y,z,qw,qx,qy,qz."""
    import sosdyn as sd

    x0 = parse_point(start, "--start")
    pushes, goals = _events(push, "--push", "2:5,0"), _events(goal_change, "--goal-change", "3:10,5")
    existing(model_path, "model file")
    if out_path is not None:
        check_output(out_path, [model_path], "model file")
        check_folder(out_path.parent)
    model = sd.load_model(model_path)
    pose = isinstance(model, PoseCDSP)
    check_angular(pose, max_angular_speed)
    sizes = POSE_SIZES if pose else {option: (model.dim_, None, None) for option in POSE_SIZES}
    x0 = _dimension(x0, sizes["--start"][0], "--start", *sizes["--start"][1:])
    for option, events in (("--push", pushes), ("--goal-change", goals)):
        for when, vector in events:
            _dimension(vector, sizes[option][0], option, *sizes[option][1:])
            if not 0 <= when <= duration:
                raise InputError(f"{option} time {when:g} is outside [0, --duration {duration:g}]. Try: a "
                                 "time within the rollout, or a longer --duration.")
    step = {} if dt is None else {"dt": dt}
    if pose:
        traj = model.rollout(x0, duration, pushes=pushes, goal_changes=goals, max_speed=max_speed,
                             max_angular_speed=max_angular_speed, **step)
        pos, names = np.hstack([traj.pos, traj.quat]), POSE_HEADER
        goal_end = max(goals, key=lambda e: e[0])[1] if goals else np.concatenate([model.goal_pos_, model.goal_quat_])
    else:
        traj = model.rollout(x0, duration, perturbations=pushes, goal_changes=goals, max_speed=max_speed, **step)
        pos, goal_end = np.asarray(traj.pos), traj.goal_history[-1]
        names = ["t", *(f"x{i + 1}" for i in range(pos.shape[1]))]
    t = np.asarray(traj.t)
    if out_path is not None:                     # the layout load_demos reads
        np.savetxt(out_path, np.column_stack([t, pos]), delimiter=",", comments="", header=",".join(names))
        info(f"[green]wrote[/] {escape(str(out_path))}  ({len(t)} steps)")
    end = ", ".join(f"{v:.4g}" for v in pos[-1])
    goal = ", ".join(f"{v:.4g}" for v in goal_end)
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
) -> None:
    """Write a standalone evaluator of a saved model (Python + numpy, or C++17).

    No sosdyn is needed to run it: Python `predict(X, goal=None) -> Xdot` with numpy only, or
    C++17 `bool predict(const double* x, double* xdot, const double* goal = nullptr)`; the goal
    can move at run time. A pose model adds `predict_pose(x, quat, goal=None) -> (v, omega)`
    (Python: numpy + scipy) or `pose_model_pose::predict_pose(x, quat, v, omega, goal)` (C++)."""
    import sosdyn as sd

    from ..lfd.runtime.export import export as generate
    from ..lfd.model.fileformat import replace_atomically

    existing(model_path, "model file")
    check_output(out_path, [model_path], "model file")
    check_folder(out_path.parent)
    model = sd.load_model(model_path)
    check_angular(isinstance(model, PoseCDSP), max_angular_speed)
    source = export_pose(model, target.value, max_speed, max_angular_speed) if isinstance(model, PoseCDSP) \
        else generate(model, target.value, max_speed)
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
                        "('demos/*.csv'), or lasa:NAME, as `sosdyn fit` takes them. Reproductions start from "
                        "their first states.", show_default=False)] = None,
    duration: Annotated[float | None, typer.Option(callback=positive, help="Seconds per reproduction; "
                                                   "default: the demonstrations' longest (10 s without).")] = None,
    dt: Annotated[float | None, typer.Option(
        callback=positive, help="Sampling step (s) of demonstration files without a time column.",
        show_default="none: the files' time column")] = None,
    time_units: TimeUnitsOption = None,
    columns: ColumnsOption = None,
) -> None:
    """Plot a saved model: streamlines, 3-D trajectories or time series.

    Streamlines for n = 2, 3-D trajectories with their projections on the box's walls for
    n = 3, each dimension of the reproductions over time for n > 3. Without --demos the
    reproductions start at the mixture's means. A pose model needs --demos (pose CSVs): 3-D
    paths with orientation frames, each rollout 3x its demo's duration unless --duration."""
    import matplotlib as mpl

    import sosdyn as sd

    from ..report.figures import STYLE, streamlines, time_series, trajectories_3d

    model_path, demos = _model_and_demos(inputs, demos)
    if out_path.suffix.lower() not in PLOT_FORMATS:
        raise InputError(f"--out {out_path} must end in .png or .svg. Try: --out {out_path.with_suffix('.png')}.")
    lasa = len(demos) == 1 and demos[0].startswith("lasa:")
    paths = [] if lasa else demo_inputs(demos)
    existing(model_path, "model file")
    check_output(out_path, [model_path, *paths], "input")
    check_folder(out_path.parent)
    model = sd.load_model(model_path)
    data = (sd.load_lasa(demos[0].removeprefix("lasa:")) if lasa
            else sd.load_demos(paths, **read_options(dt, time_units, columns))) if demos else None
    if isinstance(model, PoseCDSP):
        with status(f"rolling out {len(data or ())} reproductions ..."), mpl.rc_context(STYLE):
            plot_pose(model, data, duration, model_path.stem).savefig(
                out_path, format=out_path.suffix.lower()[1:], dpi=150, metadata=_no_date(out_path))
        info(f"[green]wrote[/] {escape(str(out_path))}  (pose model, {len(data)} demonstrations and rollouts)")
        return
    if data is not None and data.dim != model.dim_:
        raise InputError(f"the demonstrations are {data.dim}-D but the model is {model.dim_}-D. "
                         "Try: the demonstrations the model was fitted to.")
    demo_pos = [d.pos for d in data] if data is not None else []
    starts = [p[0] for p in demo_pos] or list(model.goal_ + model.scale_ * model.mixture_.means)
    horizon = duration or (max(float(d.t[-1] - d.t[0]) for d in data) if data is not None else 10.0)
    with status(f"rolling out {len(starts)} reproductions ..."):
        runs = [model.rollout(x0, horizon) for x0 in starts]
    title = model_path.stem
    if model.dim_ == 2:
        fig = streamlines(None, model.predict, demo_pos, [r.pos for r in runs], model.goal_, title=title,
                          units=model.units_)
    elif model.dim_ == 3:
        fig = trajectories_3d(demo_pos, [r.pos for r in runs], model.goal_, title=title, units=model.units_)
    else:
        fig = time_series([(r.t, r.pos) for r in runs], model.goal_, model.units_, title,
                          demos=[(d.t, d.pos) for d in data] if data is not None else ())
    with mpl.rc_context(STYLE):
        fig.savefig(out_path, format=out_path.suffix.lower()[1:], dpi=150, metadata=_no_date(out_path))
    info(f"[green]wrote[/] {escape(str(out_path))}  ({model.dim_}-D model, {len(runs)} reproductions)")


def _no_date(path: Path) -> dict:
    """savefig metadata: no creation date in an SVG, so equal inputs give equal files."""
    return {"Date": None} if path.suffix.lower() == ".svg" else {}

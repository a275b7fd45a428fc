"""Pose models in the ``sosdyn`` commands: what ``fit``, ``export`` and ``plot`` do differently for
pose CSVs (a header naming qw, qx, qy, qz: :func:`~sosdyn.lfd.data.poses.is_pose_file`) and pose model
files (format ``sosdyn-pose``; :func:`sosdyn.load_model` reads either kind).

    sosdyn fit demos/ --units cm --out pose.json        # headers t,x,y,z,qw,qx,qy,qz or ...,qx,qy,qz,qw
    sosdyn export pose.json --to python --out pose_model.py   # predict_pose(x, quat, goal=None) -> (v, omega)
    sosdyn export pose.json --to cpp --out pose.hpp     # pose_model_pose::predict_pose(x, quat, v, omega, goal)
    sosdyn plot pose.json --demos demos/ --out paths.png   # rollouts from the demos' starts, with frames
    sosdyn rollout pose.json --start 40,-20,20,0.7,0.7,0,0 --goal-change 5:30,0,20,1,0,0,0 --max-angular-speed 0.5

A pose fit preprocesses both parts of the pose (``--smooth``, ``--trim-rest``, ``--align-ends``:
:func:`~sosdyn.lfd.data.pose_preprocess.preprocess_poses`); scattered end orientations are aligned up to
``--goal-tol-deg``; ``--goal-tol`` (the position files' tolerance as recorded) is refused. ``--columns``
selects positions and so makes a position fit of the same files. After the fit: both blocks'
certificates and the reproduction table (:meth:`~sosdyn.lfd.model.pose.PoseCDSP.score`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from ..errors import InputError
from ..lfd.data.pose_preprocess import preprocess_poses
from ..lfd.data.poses import GOAL_TOL_DEG, PoseDemonstrations
from ..lfd.model.pose import PoseCDSP
from ..report.figures.poses import pose_paths
from .base import State, info, out, positive

#: ``sosdyn plot`` of a pose model without --duration: each rollout lasts this many times its demo.
DURATION_FACTOR = 3.0
#: ``sosdyn rollout`` of a pose model: the numbers each option takes, and the CSV it writes.
POSE_SIZES = {"--start": (7, "x,y,z,qw,qx,qy,qz", "0.5,0,0.3,1,0,0,0"),
              "--push": (6, "dx,dy,dz,wx,wy,wz (a world rotation vector)", "0,0,0.05,0,0,0.5"),
              "--goal-change": (7, "x,y,z,qw,qx,qy,qz", "0.5,0,0.3,1,0,0,0")}
POSE_HEADER = ["t", "x", "y", "z", "qw", "qx", "qy", "qz"]

MaxAngularSpeedOption = Annotated[float | None, typer.Option(
    "--max-angular-speed", callback=positive, help="Pose models: largest angular speed |omega| (rad/s); v and omega "
                                                   "are scaled by one factor (same path and goal).", show_default="none")]


def check_angular(pose: bool, max_angular_speed: float | None) -> None:
    """InputError for --max-angular-speed on a position model."""
    if max_angular_speed is not None and not pose:
        raise InputError("--max-angular-speed applies to pose models; this is a position model. Try: drop it "
                         "(--max-speed limits the speed).")


def open_degrees(value: float | None) -> float | None:
    """``--goal-tol-deg`` callback: a number strictly between 0 and 180 (or not given)."""
    if value is not None and not 0 < value < 180:
        raise typer.BadParameter(f"must be a number of degrees in (0, 180), both ends excluded; got {value}.")
    return value


def check_pose_options(pose: bool, goal_tol_deg: float | None, goal_tol: float | None) -> float:
    """The end-orientation tolerance of a pose fit (default GOAL_TOL_DEG); InputError for
    ``--goal-tol-deg`` with position files, or ``--goal-tol`` with pose files."""
    if not pose:
        if goal_tol_deg is not None:
            raise InputError("--goal-tol-deg applies to pose files (quaternion columns qw,qx,qy,qz). "
                             "Try: drop it, or --goal-tol for the end positions.")
        return GOAL_TOL_DEG
    if goal_tol is not None:
        raise InputError("--goal-tol applies to position files; these are pose files (quaternion columns), "
                         "whose ends are aligned by --align-ends. Try: drop it (--align-ends MAX bounds the end "
                         "positions' shift, --goal-tol-deg the end orientations), or --columns x,y,z.")
    return GOAL_TOL_DEG if goal_tol_deg is None else goal_tol_deg


def prepare_poses(data: PoseDemonstrations, smooth, trim_rest: bool, align, goal_tol_deg: float) -> PoseDemonstrations:
    """``data`` preprocessed (:func:`~sosdyn.lfd.data.pose_preprocess.preprocess_poses`), what was done printed."""
    max_shift = align if isinstance(align, float) else None
    result, report = preprocess_poses(data, smooth_window=smooth, trim_rest=trim_rest,
                                      align=True if max_shift is not None else align, max_shift=max_shift,
                                      goal_tol_deg=goal_tol_deg)
    for line in report.lines(data.units):
        info(f"preprocess: {escape(line)}")
    return result


def pose_notes(data: PoseDemonstrations) -> None:
    """What reading changed (renormalised quaternions, sign flips), one line each."""
    for note in data.notes:
        if "renormalised" in note or "sign-flipped" in note:
            info(f"read: {escape(note)}")


def pose_fit_summary(model: PoseCDSP, data: PoseDemonstrations) -> None:
    """The orientation block's certificate, still blocks, end orientations turned, and the reproduction table."""
    report = model.orientation_.verification_
    info(f"orientation certificate (identity metric: the angle to the goal never increases): "
         f"{'[green]passed[/]' if report.passed else '[red]FAILED[/]'} — min Gram eigenvalue {report.min_gram_eig:.2e}, "
         f"max sampled eigenvalue {report.max_sampled_eig:.2e} over {report.n_samples} states")
    for block, rate in model.still_.items():
        if rate is not None:
            info(f"the {block} does not move in the demonstrations: it is held at the goal (returns at rate "
                 f"{rate:.3g}/s if pushed)")
    moved = ", ".join(f"{a:.2g}" for a in model.orientation_moved_deg_)
    info(f"end orientations aligned onto their chordal mean by {moved} deg (refused beyond --goal-tol-deg "
         f"{model.goal_tol_deg:g})")
    if State.quiet:
        return
    rows = model.score(data)
    u = data.units or "units"
    out.print(f"reproduction of each demonstration from its start (positions in {u}, angles in deg; at goal = "
              "within 1% of the extent and 1 deg):", highlight=False, soft_wrap=True)
    out.print(f"{'demo':>4}  {'mean dev':>10}  {'max dev':>10}  {'mean deg':>8}  {'max deg':>8}  {'arrival s':>9}  "
              f"{'demo s':>7}  at goal", highlight=False)
    for r in rows:
        out.print(f"{r['demo']:>4}  {r['mean_dev']:>10.4g}  {r['max_dev']:>10.4g}  {r['mean_dev_deg']:>8.3g}  "
                  f"{r['max_dev_deg']:>8.3g}  {r['arrival_s']:>9.3g}  {r['duration_s']:>7.3g}  "
                  f"{'yes' if r['at_goal'] else 'NO'}", highlight=False)


def export_pose(model: PoseCDSP, target: str, max_speed: float | None, max_angular_speed: float | None) -> str:
    """The standalone source of a pose model for ``target`` ("python" or "cpp"), with the limits on
    |v| and |omega| written into it."""
    return model.export(target, max_speed, max_angular_speed)


def plot_pose(model: PoseCDSP, data: PoseDemonstrations | None, duration: float | None, title: str):
    """The figure of a pose model: each demo and the model's rollout from its start, with frames."""
    if not isinstance(data, PoseDemonstrations):
        raise InputError("a pose model is drawn with the pose demonstrations it starts from. Try: --demos "
                         "with pose CSVs (t,x,y,z,qw,qx,qy,qz), e.g. the files it was fitted to.")
    trajs = [model.rollout(np.concatenate([d.pos[0], d.quat[0]]), duration or DURATION_FACTOR * (d.t[-1] - d.t[0]))
             for d in data]
    return pose_paths(title, [], list(data), trajs, model.goal_pos_, model.units_,
                      [Path(d.source).stem for d in data])

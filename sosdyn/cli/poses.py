"""Pose models in the ``sosdyn`` commands: what ``fit``, ``export`` and ``plot`` do differently for
pose CSVs (a header naming qw, qx, qy, qz: :func:`~sosdyn.lfd.data.pose.is_pose_file`) and pose model
files (format ``sosdyn-pose``; :func:`sosdyn.load_model` reads either kind).

    sosdyn fit demos/ --units cm --out pose.json        # headers t,x,y,z,qw,qx,qy,qz or ...,qx,qy,qz,qw
    sosdyn export pose.json --to python --out pose_model.py   # predict_pose(x, quat, goal=None) -> (v, omega)
    sosdyn export pose.json --to cpp --out pose.hpp     # pose_model_pose::predict_pose(x, quat, v, omega, goal)
    sosdyn plot pose.json --demos demos/ --out paths.png   # rollouts from the demos' starts, with frames
    sosdyn rollout pose.json --start 40,-20,20,0.7,0.7,0,0 --goal-change 5:30,0,20,1,0,0,0 --max-angular-speed 0.5

A pose fit reads no position-only option (``--goal-tol``, ``--smooth``, ``--trim-rest``,
``--align-ends``: refused when given); scattered end orientations are aligned up to
``--goal-tol-deg``. ``--columns`` selects positions and so makes a position fit of the same files.
"""
from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.markup import escape

from ..errors import InputError
from ..lfd.data.pose import GOAL_TOL_DEG, PoseDemonstrations
from ..lfd.model.pose import PoseCDSP
from ..lfd.runtime.pose import pose_to_cpp, pose_to_python
from ..report.figures.poses import pose_paths
from .base import info, positive

#: ``sosdyn plot`` of a pose model without --duration: each rollout lasts this many times its demo.
DURATION_FACTOR = 3.0
#: ``sosdyn rollout`` of a pose model: the numbers each option takes, and the CSV it writes.
POSE_SIZES = {"--start": (7, "x,y,z,qw,qx,qy,qz"), "--push": (6, "dx,dy,dz,wx,wy,wz (a world rotation vector)"),
              "--goal-change": (7, "x,y,z,qw,qx,qy,qz")}
POSE_HEADER = ["t", "x", "y", "z", "qw", "qx", "qy", "qz"]

MaxAngularSpeedOption = Annotated[float | None, typer.Option(
    "--max-angular-speed", callback=positive, help="Pose models: largest angular speed |omega| (rad/s); v and omega "
                                                   "are scaled by one factor (same path and goal).", show_default="none")]


def check_angular(pose: bool, max_angular_speed: float | None) -> None:
    """InputError for --max-angular-speed on a position model."""
    if max_angular_speed is not None and not pose:
        raise InputError("--max-angular-speed applies to pose models; this is a position model. Try: drop it "
                         "(--max-speed limits the speed).")


def check_pose_options(pose: bool, goal_tol_deg: float | None, position_only: dict) -> float:
    """The end-orientation tolerance of a pose fit (default GOAL_TOL_DEG); InputError for
    ``--goal-tol-deg`` with position files, or for a position-only option given (not None) with pose files."""
    if not pose:
        if goal_tol_deg is not None:
            raise InputError("--goal-tol-deg applies to pose files (quaternion columns qw,qx,qy,qz). "
                             "Try: drop it, or --goal-tol for the end positions.")
        return GOAL_TOL_DEG
    given = [name for name, value in position_only.items() if value is not None]
    if given:
        raise InputError(f"{', '.join(given)} apply to position files; these are pose files (quaternion "
                         "columns), fitted without preprocessing. Try: drop them (--goal-tol-deg bounds the "
                         "end orientations), or --columns x,y,z for a position model.")
    return GOAL_TOL_DEG if goal_tol_deg is None else goal_tol_deg


def pose_notes(data: PoseDemonstrations) -> None:
    """What reading changed (renormalised quaternions, sign flips), one line each."""
    for note in data.notes:
        if "renormalised" in note or "sign-flipped" in note:
            info(f"read: {escape(note)}")


def pose_fit_summary(model: PoseCDSP) -> None:
    """How far each demo's end orientation was turned onto the goal orientation."""
    moved = ", ".join(f"{a:.2g}" for a in model.orientation_moved_deg_)
    info(f"end orientations aligned onto their chordal mean by {moved} deg (refused beyond --goal-tol-deg "
         f"{model.goal_tol_deg:g}); certificate on the 6-D chart state (position, rotation vector)")


def export_pose(model: PoseCDSP, target: str, max_speed: float | None, max_angular_speed: float | None) -> str:
    """The standalone source of a pose model for ``target`` ("python" or "cpp"), with the limits on
    |v| and |omega| written into it."""
    return pose_to_python(model, max_speed, max_angular_speed) if target == "python" else \
        pose_to_cpp(model, max_speed=max_speed, max_angular_speed=max_angular_speed)


def plot_pose(model: PoseCDSP, data: PoseDemonstrations | None, duration: float | None, title: str):
    """The figure of a pose model: each demo and the model's rollout from its start, with frames."""
    if not isinstance(data, PoseDemonstrations):
        raise InputError("a pose model is drawn with the pose demonstrations it starts from. Try: --demos "
                         "with pose CSVs (t,x,y,z,qw,qx,qy,qz), e.g. the files it was fitted to.")
    trajs = [model.rollout(np.concatenate([d.pos[0], d.quat[0]]), duration or DURATION_FACTOR * (d.t[-1] - d.t[0]))
             for d in data]
    return pose_paths(title, [], list(data), trajs, model.goal_pos_, model.cdsp_.units_,
                      [Path(d.source).stem for d in data])

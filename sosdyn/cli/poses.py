"""``sosdyn fit-pose`` and ``sosdyn export-pose``: pose CSVs (t,x,y,z + a quaternion) to a certified
:class:`~sosdyn.lfd.model.pose.PoseCDSP` file, and that file to a standalone Python evaluator.

    sosdyn fit-pose demos/ --units cm --out pose.json        # headers t,x,y,z,qw,qx,qy,qz or ...,qx,qy,qz,qw
    sosdyn export-pose pose.json --out pose_model.py         # predict_pose(x, quat, goal=None) -> (v, omega)
    sosdyn plot-pose pose.json --demos demos/ --out paths.png   # rollouts from the demos' starts, with frames
    sosdyn export-pose pose.json --cpp --out pose.hpp     # pose_model_pose::predict_pose(x, quat, v, omega, goal)
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from typing import Annotated

import typer
from rich.markup import escape

from ..errors import InputError

from ..lfd.data.poses import GOAL_TOL_DEG, load_pose_demos
from ..lfd.model.fileformat import replace_atomically
from ..lfd.model.pose import PoseCDSP, load_pose_model
from ..lfd.model.pose_export import pose_to_cpp, pose_to_python
from ..report.figures.poses import pose_paths
from .base import app, info, positive
from .paths import check_folder, check_output, demo_inputs, existing


@app.command("fit-pose")
def fit_pose(
    demos: Annotated[list[str], typer.Argument(help="Pose CSV files (header t,x,y,z,qw,qx,qy,qz or "
                                                    "t,x,y,z,qx,qy,qz,qw), folders or quoted patterns.",
                                               show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="Where to save the pose model (JSON).")] = Path(
        "pose.json"),
    units: Annotated[str, typer.Option(help="Units of the positions (recorded, not applied).")] = "",
    dt: Annotated[float | None, typer.Option(callback=positive, help="Sampling step (s) of files without a "
                                                                     "time column.")] = None,
    goal_tol_deg: Annotated[float, typer.Option(help="Refuse end orientations farther than this (deg) from "
                                                     "their mean; nearer ones are aligned to it.")] = GOAL_TOL_DEG,
) -> None:
    """Learn a certified pose model (position + orientation) from pose CSVs and save it."""
    paths = demo_inputs(demos)
    check_output(out_path, paths, "demonstration file")
    check_folder(out_path.parent)
    data = load_pose_demos(paths, units=units, dt=dt)
    for note in data.notes:
        if "renormalised" in note or "sign-flipped" in note:
            info(escape(note))
    start = time.perf_counter()
    model = PoseCDSP(goal_tol_deg=goal_tol_deg).fit(data)
    model.save(out_path)
    report = model.cdsp_.verification_
    moved = ", ".join(f"{a:.1f}" for a in model.orientation_moved_deg_)
    info(f"[green]saved[/] {escape(str(out_path))}  ({len(data)} pose demonstrations, fit in "
         f"{time.perf_counter() - start:.1f} s); end orientations aligned by {moved} deg")
    info(f"certificate (6-D chart model): {'[green]passed[/]' if report.passed else '[red]FAILED[/]'} — min Gram "
         f"eigenvalue {report.min_gram_eig:.2e}, max sampled generalised eigenvalue {report.max_sampled_eig:.2e}")


@app.command("export-pose")
def export_pose(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit-pose`.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The file to write (.py or .hpp).",
                                           show_default=False)],
    cpp: Annotated[bool, typer.Option("--cpp", help="A header-only C++17 evaluator instead of Python.")] = False,
) -> None:
    """Write a standalone evaluator of a pose model, predict_pose -> (v, omega): Python (numpy + scipy)
    or, with --cpp, header-only C++17 (namespace pose_model_pose)."""
    existing(model_path, "model file")
    check_output(out_path, [model_path], "model file")
    check_folder(out_path.parent)
    source = (pose_to_cpp if cpp else pose_to_python)(load_pose_model(model_path))
    replace_atomically(out_path, source.encode("utf-8"))
    info(f"[green]wrote[/] {escape(str(out_path))}  ({'cpp' if cpp else 'python'}, {len(source.splitlines())} lines)")


@app.command("plot-pose")
def plot_pose(
    model_path: Annotated[Path, typer.Argument(help="A model saved by `sosdyn fit-pose`.", show_default=False)],
    demos: Annotated[list[str], typer.Option(help="Pose CSVs (files, folders, patterns): drawn, and the model "
                                                  "rolled out from each one's start.", show_default=False)],
    out_path: Annotated[Path, typer.Option("--out", "-o", help="The figure (.png or .svg).")] = Path("pose.png"),
    duration_factor: Annotated[float, typer.Option(callback=positive, help="Rollout duration over each "
                                                                           "demo's duration.")] = 3.0,
) -> None:
    """Draw the demos and the model's rollouts from their starts in 3-D, with orientation frames."""
    existing(model_path, "model file")
    paths = demo_inputs(demos)
    check_output(out_path, [model_path, *paths], "input")
    check_folder(out_path.parent)
    if out_path.suffix.lower() not in (".png", ".svg"):
        raise InputError(f"--out {out_path.name}: the figure is written as .png or .svg. Try: --out pose.png")
    model = load_pose_model(model_path)
    data = load_pose_demos(paths)
    trajs = [model.rollout(np.concatenate([d.pos[0], d.quat[0]]), duration_factor * (d.t[-1] - d.t[0]))
             for d in data]
    fig = pose_paths(model_path.stem, [], list(data), trajs, model.goal_pos_, model.cdsp_.units_,
                     [Path(d.source).stem for d in data])
    fig.savefig(out_path, dpi=130)
    info(f"[green]wrote[/] {escape(str(out_path))}  ({len(data)} demonstrations and rollouts)")

"""The figures of ``make poses``: 3-D paths with orientation frames, angle to the goal over time."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.evaluation.poses import angles_deg
from sosdyn.report.figures.style import new_figure, styled

ROLLOUT_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7")
FRAME_COLORS = ("#d62728", "#2ca02c", "#1f77b4")     # x, y, z axes of a frame
N_FRAMES = 7
FLOOR = 1e-3                 # angles below this (deg) are drawn at it (log axis)


def draw_frames(ax, pos, quat, length: float) -> None:
    """Orientation triads (x red, y green, z blue) at N_FRAMES samples equally spaced along pos."""
    idx = np.unique(np.linspace(0, len(pos) - 1, N_FRAMES).astype(int))
    axes = Rotation.from_quat(quat[idx], scalar_first=True).as_matrix() * length     # columns = body axes
    for k, color in enumerate(FRAME_COLORS):
        ax.quiver(*pos[idx].T, *axes[:, :, k].T, color=color, lw=1.0, arrow_length_ratio=0.0)


@styled
def paths_figure(task, train, test, trajs, model, path: Path) -> Path:
    fig = new_figure(7.0, 5.6)
    ax = fig.add_subplot(projection="3d")
    allp = np.vstack([d.pos for d in train])
    for d in train:
        ax.plot(*d.pos.T, color="0.7", lw=1)
    for i, (d, tr) in enumerate(zip(test, trajs)):
        ax.plot(*d.pos.T, color="k", lw=1, ls="--", label="test demo" if i == 0 else None)
        color = ROLLOUT_COLORS[i % len(ROLLOUT_COLORS)]
        ax.plot(*tr.pos.T, color=color, lw=2, label=f"rollout from demo {5 + i}")
        draw_frames(ax, tr.pos, tr.quat, 0.06 * float(np.ptp(allp, axis=0).max()))
    ax.scatter(*model.goal_pos_, color="k", marker="*", s=80, label="goal")
    extent = np.ptp(np.vstack([allp] + [tr.pos for tr in trajs]), axis=0)
    ax.set_box_aspect(np.maximum(extent, 0.4 * extent.max()))       # near-equal scales, no axis squashed flat
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.set_zlabel("z (cm)")
    ax.set_title(f"{task}: paths and orientation frames")
    ax.legend(loc="upper left", fontsize=7)
    fig.savefig(path, dpi=130)
    return path


@styled
def orientation_error_figure(task, test, trajs, model, path: Path) -> Path:
    fig = new_figure(7.0, 3.0)
    ax = fig.add_subplot()
    for i, (d, tr) in enumerate(zip(test, trajs)):
        color = ROLLOUT_COLORS[i % len(ROLLOUT_COLORS)]
        ax.plot(d.t - d.t[0], np.maximum(angles_deg(d.quat, model.goal_quat_), FLOOR), color=color, ls="--", lw=1)
        ax.plot(tr.t, np.maximum(angles_deg(tr.quat, model.goal_quat_), FLOOR), color=color, lw=1.8,
                label=f"demo {5 + i}")
    ax.axhline(1.0, color="0.4", ls=":", lw=1)
    ax.set_yscale("log")
    ax.set_ylim(FLOOR, 200)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("angle to goal (deg)")
    ax.set_title(f"{task}: orientation error (dashed: test demo, solid: rollout)")
    ax.legend(ncol=4, loc="upper right")
    fig.savefig(path, dpi=130)
    return path

"""Pose figures: 3-D paths with orientation frames, and the angle to the goal orientation over time.

Both take plain data: demonstrations with ``.t``, ``.pos`` (T, 3), ``.quat`` (T, 4, w x y z) and
rollouts with the same fields; they return a :class:`matplotlib.figure.Figure`.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.evaluation.poses import angles_deg
from .style import axis_label, new_figure, styled

ROLLOUT_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9")
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
def pose_paths(title, background, demos, trajs, goal_pos, units: str = "", labels=None, names=("x", "y", "z")):
    """Background demos (grey), demos (black, dashed) and rollouts (colour) with frames, the goal (star)."""
    fig = new_figure(7.0, 5.6)
    ax = fig.add_subplot(projection="3d")
    allp = np.vstack([d.pos for d in list(background) + list(demos)])
    for d in background:
        ax.plot(*d.pos.T, color="0.7", lw=1)
    for i, (d, tr) in enumerate(zip(demos, trajs)):
        ax.plot(*d.pos.T, color="k", lw=1, ls="--", label="demo" if i == 0 else None)
        ax.plot(*tr.pos.T, color=ROLLOUT_COLORS[i % len(ROLLOUT_COLORS)], lw=2,
                label=f"rollout from {labels[i] if labels else f'demo {i}'}")
        draw_frames(ax, tr.pos, tr.quat, 0.06 * float(np.ptp(allp, axis=0).max()))
    ax.scatter(*goal_pos, color="k", marker="*", s=80, label="goal")
    extent = np.ptp(np.vstack([allp] + [tr.pos for tr in trajs]), axis=0)
    ax.set_box_aspect(np.maximum(extent, 0.4 * extent.max()))       # near-equal scales, no axis squashed flat
    ax.set_xlabel(axis_label(0, units, names))
    ax.set_ylabel(axis_label(1, units, names))
    ax.set_zlabel(axis_label(2, units, names))
    ax.set_title(f"{title}: paths and orientation frames")
    ax.legend(loc="upper left", fontsize=7)
    return fig


@styled
def orientation_error(title, demos, trajs, goal_quat, labels=None):
    """Angle to the goal orientation (deg, log axis) over time: demos dashed, rollouts solid; 1 deg dotted."""
    fig = new_figure(7.0, 3.0)
    ax = fig.add_subplot()
    for i, (d, tr) in enumerate(zip(demos, trajs)):
        color = ROLLOUT_COLORS[i % len(ROLLOUT_COLORS)]
        ax.plot(d.t - d.t[0], np.maximum(angles_deg(d.quat, goal_quat), FLOOR), color=color, ls="--", lw=1)
        ax.plot(tr.t, np.maximum(angles_deg(tr.quat, goal_quat), FLOOR), color=color, lw=1.8,
                label=labels[i] if labels else f"demo {i}")
    ax.axhline(1.0, color="0.4", ls=":", lw=1)
    ax.set_yscale("log")
    ax.set_ylim(FLOOR, 200)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("angle to goal (deg)")
    ax.set_title(f"{title}: orientation error (dashed: demo, solid: rollout)")
    ax.legend(ncol=4, loc="upper right")
    return fig


@styled
def detour_figure(title, cases, diag: float, units: str = ""):
    """The detour tests over time: angle to the goal orientation (left) and the position's distance from
    where it started, in % of the data's diagonal (right), one line per case (``cases``: dicts with kind,
    angle_deg, t, angle, displacement; :func:`sosdyn.evaluation.poses.detour_tests`)."""
    fig = new_figure(9.0, 3.2)
    left, right = fig.subplots(1, 2)
    styles = {"orientation-only start": "-", "goal turn": "--"}
    angles = sorted({c["angle_deg"] for c in cases})
    for c in cases:
        color = ROLLOUT_COLORS[angles.index(c["angle_deg"]) % len(ROLLOUT_COLORS)]
        label = f"{c['kind']}, {c['angle_deg']:g} deg"
        first = all(other is c or (other["kind"], other["angle_deg"]) != (c["kind"], c["angle_deg"])
                    for other in cases[:cases.index(c) + 1])
        left.plot(c["t"], c["angle"], color=color, ls=styles[c["kind"]], lw=1.2, label=label if first else None)
        right.plot(c["t"], 100.0 * c["displacement"] / diag, color=color, ls=styles[c["kind"]], lw=1.2)
    left.axhline(1.0, color="0.4", ls=":", lw=1)
    left.set_ylim(0, 185)
    left.set_xlabel("t (s)")
    left.set_ylabel("angle to goal orientation (deg)")
    left.legend(fontsize=7, loc="upper right")
    right.axhline(1.0, color="0.4", ls=":", lw=1)
    right.set_ylim(-0.05, 1.5)
    right.set_xlabel("t (s)")
    right.set_ylabel(f"position moved (% of diagonal {diag:.3g}{' ' + units if units else ''})")
    worst = max(c["displacement"].max() for c in cases)
    right.set_title(f"largest: {worst:.3g}{' ' + units if units else ''} (dotted: the 1 % target)", fontsize=9)
    fig.suptitle(f"{title}: orientation-only starts (solid) and goal turns after arrival (dashed)")
    return fig


@styled
def drift_figure(tasks, target: float):
    """Each recorded training demo as a reproduction of the test demos, in recording order: its mean DTW
    over the test demos divided by the mean of the nearest copy (left: position DTWD, right: orientation
    DTW), one line per task, the model's ratio drawn at the right end, ``target`` dotted. ``tasks``: dicts
    with task, train_pos / train_ori ((tests, demos) DTWs), copy_pos / copy_ori and pos_ratio / ori_ratio."""
    fig = new_figure(9.0, 3.2)
    axes = fig.subplots(1, 2, sharey=True)
    for ax, part, name in zip(axes, ("pos", "ori"), ("position DTWD", "orientation DTW")):
        for i, t in enumerate(tasks):
            each = np.mean(t[f"train_{part}"], axis=0) / t[f"copy_{part}"]
            color = ROLLOUT_COLORS[i % len(ROLLOUT_COLORS)]
            ax.plot(np.arange(len(each)), each, "o-", color=color, lw=1.2, ms=4, label=t["task"])
            ax.plot(len(each) + 0.5, t[f"{part}_ratio"], "*", color=color, ms=11)
        ax.axhline(target, color="0.4", ls=":", lw=1)
        ax.axhline(1.0, color="0.7", lw=0.8)
        n = max(len(np.mean(t[f"train_{part}"], axis=0)) for t in tasks)
        ax.set_xticks(list(range(n)) + [n + 0.5], [str(k + 1) for k in range(n)] + ["model"])
        ax.set_xlabel("training demo, in recording order")
        ax.set_title(f"{name} / copy", fontsize=9)
    axes[0].set_ylabel("mean over the test demos / copy")
    axes[0].set_ylim(0, None)
    axes[1].legend(fontsize=7, loc="upper right")
    fig.suptitle("each training demo replayed against the (later) test demos; the star: the model")
    return fig

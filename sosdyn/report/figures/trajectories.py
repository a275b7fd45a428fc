"""State-space trajectories: perturbed runs of every method (paper Fig. 4) and 3-D reproductions."""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import FancyArrowPatch
from matplotlib.ticker import MaxNLocator

from .style import (DEMO_COLOR, GOAL_STYLE, REPRO_COLOR, as_xy, axis_label, data_bounds, finish_state_axes, method_color,
                    new_figure, stream_legend_handles, styled)


@styled
def perturbation_trajectories(ax, demo, runs: Mapping[str, np.ndarray],
                              events: Sequence[Mapping] | Mapping[str, Sequence[Mapping]] = (),
                              goal_history=None,
                              title: str | None = None, *, units: str = "mm",
                              methods: Sequence[str] = ()) -> Figure:
    """Paper Fig. 4: each method's reproduction under a push or a goal change.

    ``demo`` (T, 2) is drawn as a wide light-gray band, each entry of ``runs``
    (method -> (T, 2) positions) in its method colour. Pushes are arrows from the state
    before to the state after, taken from ``events`` in the format of
    ``Trajectory.events`` (dicts with ``kind``, ``before``, ``after``; only
    ``kind == "push"`` is drawn): either one list (arrows in black, or in the colour of
    an optional ``"method"`` key) or a dict method -> that method's events, e.g.
    ``{m: traj.events for m, traj in trajs.items()}``. ``goal_history`` ((T, 2), the
    goal in force at each step) gives the goal markers: the first goal hollow ("old
    goal") and every later distinct goal filled ("new goal"); a constant history is
    one "goal" star. ``methods``: the report's full method list, so that a panel showing
    only some of them colours each as the other figures do (:func:`~.style.method_color`);
    default: the keys of ``runs``.

    With ``ax=None`` a new figure with the legend underneath is returned, otherwise
    ``ax.figure``.
    """
    own_figure = ax is None
    if own_figure:
        fig = new_figure(4.6, 5.2)
        ax = fig.add_subplot()
    demo = as_xy(demo)
    methods = list(methods) or list(runs)
    handles = [Line2D([], [], color="0.75", lw=5, alpha=0.8, solid_capstyle="round",
                      label="demonstration")]
    ax.plot(demo[:, 0], demo[:, 1], color="0.75", lw=5, alpha=0.8, solid_capstyle="round", zorder=1)
    for method, pos in runs.items():
        pos = as_xy(pos)
        (line,) = ax.plot(pos[:, 0], pos[:, 1], color=method_color(method, methods), lw=1.6,
                          zorder=3, label=method)
        handles.append(line)

    tagged = ([{"method": m, **e} for m, evs in events.items() for e in evs]
              if isinstance(events, Mapping) else list(events))
    pushes = [e for e in tagged if e.get("kind") == "push"]
    for e in pushes:
        color = method_color(e["method"], methods) if e.get("method") else "black"
        ax.add_patch(FancyArrowPatch(np.asarray(e["before"], dtype=float)[:2],
                                     np.asarray(e["after"], dtype=float)[:2], arrowstyle="-|>",
                                     mutation_scale=12, color=color, lw=1.4, zorder=5))
    if pushes:
        handles.append(Line2D([], [], color="black", lw=1.4, marker=">", markersize=5,
                              label="push"))

    all_pts = [demo, *(as_xy(p) for p in runs.values())]
    if goal_history is not None:
        goals = np.asarray(goal_history, dtype=float)[:, :2]
        distinct = goals[np.r_[True, np.any(np.diff(goals, axis=0) != 0, axis=1)]]
        all_pts.append(distinct)
        if len(distinct) == 1:
            ax.plot(*distinct[0], **GOAL_STYLE)
            handles.append(Line2D([], [], label="goal", **GOAL_STYLE))
        else:
            hollow = {**GOAL_STYLE, "markerfacecolor": "white", "markeredgecolor": "black"}
            ax.plot(*distinct[0], **hollow)
            ax.plot(distinct[1:, 0], distinct[1:, 1], **GOAL_STYLE)
            handles += [Line2D([], [], label="old goal", **hollow),
                        Line2D([], [], label="new goal", **GOAL_STYLE)]

    return finish_state_axes(ax, data_bounds(all_pts, pad=0.06, square=True), units, title,
                             handles if own_figure else None, ncols=min(len(handles), 4))


@styled
def trajectories_3d(demos: Sequence[np.ndarray], reproductions: Sequence[np.ndarray], goal,
                    title: str | None = None, *, units: str = "mm", names=None) -> Figure:
    """3-D demonstrations (solid red) and reproductions (dashed blue) with the goal, and their
    projections on the three back walls of the box (the x1-x2 floor, the x1-x3 and x2-x3 walls;
    thin, light), which show the paths' shape whatever the view angle.

    The box follows the data ranges (true proportions), except that no side is drawn
    shorter than 35 % of the longest, so a nearly planar motion keeps readable ticks.
    """
    fig = new_figure(5.4, 5.0)
    ax = fig.add_subplot(projection="3d")
    demos = [np.asarray(d, dtype=float)[:, :3] for d in demos]
    repros = [np.asarray(r, dtype=float)[:, :3] for r in reproductions]
    goal = np.asarray(goal, dtype=float)[:3]
    points = np.vstack([*demos, *repros, goal[None, :]])
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.04 * np.maximum(hi - lo, 1e-9 + 0.01 * (hi - lo).max())
    lo, hi = lo - pad, hi + pad
    # back walls for the default view (azim -60, elev 30): z = lo, y = hi, x = lo
    walls = ((2, lo[2]), (1, hi[1]), (0, lo[0]))
    for paths, color, style in ((demos, DEMO_COLOR, "-"), (repros, REPRO_COLOR, (0, (4, 2.5)))):
        for p in paths:
            for axis, value in walls:
                q = p.copy()
                q[:, axis] = value
                ax.plot(q[:, 0], q[:, 1], q[:, 2], color=color, lw=0.8, ls=style, alpha=0.35)
            ax.plot(p[:, 0], p[:, 1], p[:, 2], color=color, lw=1.5, ls=style)
    for axis, value in walls:
        g = goal.copy()
        g[axis] = value
        ax.plot([g[0]], [g[1]], [g[2]], **{**GOAL_STYLE, "alpha": 0.35, "markersize": 7})
    ax.plot([goal[0]], [goal[1]], [goal[2]], **GOAL_STYLE)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ranges = hi - lo
    ax.set_box_aspect(np.maximum(ranges, 0.35 * ranges.max() + 1e-9), zoom=0.88)
    for i, axis in enumerate((ax.xaxis, ax.yaxis, ax.zaxis)):
        axis.set_major_locator(MaxNLocator(4))
        axis.set_label_text(axis_label(i, units, names))
    if title:
        ax.set_title(title)
    handles = stream_legend_handles(bool(demos))[1:] + [
        Line2D([], [], color="0.5", lw=0.8, alpha=0.5, label="projections on the walls")]
    fig.legend(handles=handles, loc="outside lower center", ncols=2)
    return fig


# -------------------------------------------------------------------------- bar charts


@styled
def time_series(runs: Sequence[tuple[np.ndarray, np.ndarray]], goal, units: str = "mm",
                title: str | None = None, demos: Sequence[tuple[np.ndarray, np.ndarray]] = (), names=None) -> Figure:
    """One panel per dimension: x_i(t) of every reproduction ``(t, pos)`` in ``runs`` (dashed
    blue) over the demonstrations ``demos`` (solid red, as in the 2-D figures), the goal's x_i
    dotted (the view of a model in more than three dimensions)."""
    n = len(goal)
    fig = new_figure(6.0, 1.6 * n + 0.9)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for i, ax in enumerate(axes):
        for t, pos in demos:
            ax.plot(t, pos[:, i], color=DEMO_COLOR, lw=1.0, alpha=0.8)
        for t, pos in runs:
            ax.plot(t, pos[:, i], color=REPRO_COLOR, lw=1.3, ls="--")
        ax.axhline(goal[i], color="black", ls=":", lw=1.0)
        ax.set_ylabel(axis_label(i, units, names))
    axes[-1].set_xlabel("t (s)")
    if title:
        axes[0].set_title(title)
    handles = ([Line2D([], [], color=DEMO_COLOR, lw=1.0, label="demonstrations")] if len(demos) else []) + [
        Line2D([], [], color=REPRO_COLOR, lw=1.3, ls="--", label="reproductions"),
        Line2D([], [], color="black", ls=":", lw=1.0, label="goal")]
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles))
    return fig

"""Paper Fig. 1: streamlines of a learned 2-D field with its demonstrations and reproductions."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from .style import (DEMO_COLOR, GOAL_STYLE, REPRO_COLOR, STREAM_COLOR, as_xy, data_bounds, finish_state_axes,
                    new_figure, stream_legend_handles, styled)


# ----------------------------------------------------------------- state-space plots

@styled
def streamlines(ax, predict: Callable[[np.ndarray], np.ndarray] | None,
                demos_pos: Sequence[np.ndarray], reproductions: Sequence[np.ndarray],
                goal, bounds: tuple[float, float, float, float] | None = None,
                title: str | None = None, *, units: str = "mm", grid: int = 70,
                density: float = 1.1, names=None) -> Figure:
    """Paper Fig. 1: a learned 2-D vector field with the data it was learned from.

    Gray streamlines of ``predict(X) -> Xdot`` on a ``grid`` x ``grid`` lattice over
    ``bounds`` ((xmin, xmax, ymin, ymax); default: the square around demonstrations,
    reproductions and goal, padded by 10 %), the demonstrations as solid red lines,
    the reproductions (rollouts from the demonstrations' starts) as dashed blue lines
    and the goal as a black star. ``predict=None`` (e.g. a time-indexed DMP, which has
    no field) draws the trajectories only. ``names``: the axes' names (default $x_1$, $x_2$).

    With ``ax=None`` a new figure with its legend underneath is returned; with an
    ``ax`` the plot goes there, the caller owns the legend, and ``ax.figure`` is
    returned.
    """
    demos = [as_xy(d) for d in demos_pos]
    repros = [as_xy(r) for r in reproductions]
    goal = np.asarray(goal, dtype=float)[:2]
    own_figure = ax is None
    if own_figure:
        fig = new_figure(4.4, 5.0)
        ax = fig.add_subplot()
    xmin, xmax, ymin, ymax = bounds or data_bounds([*demos, *repros, goal[None, :]], square=True)

    if predict is not None:
        gx, gy = np.linspace(xmin, xmax, grid), np.linspace(ymin, ymax, grid)
        X, Y = np.meshgrid(gx, gy)
        V = np.asarray(predict(np.column_stack([X.ravel(), Y.ravel()])), dtype=float)
        U = np.ma.masked_invalid(V[:, 0].reshape(X.shape))
        W = np.ma.masked_invalid(V[:, 1].reshape(X.shape))
        ax.streamplot(gx, gy, U, W, color=STREAM_COLOR, linewidth=0.6, density=density,
                      arrowsize=0.7, zorder=1)
    for d in demos:
        ax.plot(d[:, 0], d[:, 1], color=DEMO_COLOR, lw=1.6, zorder=3, solid_capstyle="round")
    for r in repros:
        ax.plot(r[:, 0], r[:, 1], color=REPRO_COLOR, lw=1.6, ls=(0, (4, 2.5)), zorder=4)
    ax.plot(*goal, **GOAL_STYLE)

    return finish_state_axes(ax, (xmin, xmax, ymin, ymax), units, title,
                             stream_legend_handles(bool(demos), predict is not None) if own_figure else None, names=names)


@styled
def streamline_panel(panels: Sequence[Mapping], *, ncols: int | None = None,
                     panel_size: float = 3.0, units: str = "mm") -> Figure:
    """Several :func:`streamlines` plots in a grid with one shared legend underneath.

    Each panel is a dict of :func:`streamlines` keyword arguments (``predict``,
    ``demos_pos``, ``reproductions``, ``goal``, optional ``bounds``, ``title``, ``grid``,
    ``density``; a 30-panel grid defaults to a coarser field).
    Used for the paper's four shapes (one row) and for all 30 LASA shapes (6 columns).
    Axis labels are written on the outer panels only.
    """
    if not panels:
        raise ValueError("streamline_panel needs at least one panel")
    n = len(panels)
    ncols = ncols or min(n, 4 if n <= 8 else 6)
    nrows = -(-n // ncols)
    fig = new_figure(panel_size * ncols, panel_size * nrows + 0.45)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    dense = n > 8
    for i, ax in enumerate(axes.flat):
        if i >= n:
            ax.set_visible(False)
            continue
        spec = {"predict": None, "reproductions": (), "units": units,
                "grid": 50 if dense else 70, "density": 0.8 if dense else 1.1, **panels[i]}
        streamlines(ax, **spec)
        if i + ncols < n:           # a panel below this one carries the x label
            ax.set_xlabel("")
        if i % ncols:
            ax.set_ylabel("")
        if dense:
            ax.tick_params(labelsize=6.5)
            ax.title.set_fontsize(8.5)
    fig.legend(handles=stream_legend_handles(), loc="outside lower center", ncols=4)
    return fig

"""Publication figures for sosdyn reports (matplotlib, no pyplot state).

Every function takes plain data (arrays, callables, dicts shaped like the results
schema in :mod:`sosdyn.report.html`) and returns a :class:`matplotlib.figure.Figure`;
:func:`save_figure` writes it as SVG and PNG. Figures are built on
``matplotlib.figure.Figure`` directly, so nothing is registered with pyplot, nothing
leaks between calls and no GUI backend is ever needed.

Conventions shared by all figures:

* each method has one colour everywhere (:func:`method_color`), so CDSP is the same
  blue in the bar charts, the perturbation plots and the scaling plots;
* 2-D state-space plots use an equal aspect ratio and axes labelled in ``units``;
* legends sit outside the data (under or above the axes), never on top of it;
* layout is matplotlib's constrained layout.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import FancyArrowPatch, Patch
from matplotlib.ticker import FuncFormatter, MaxNLocator

__all__ = [
    "METRIC_LABELS",
    "accuracy_bars",
    "method_color",
    "perturbation_trajectories",
    "robustness_bars",
    "save_figure",
    "scaling_plot",
    "streamline_panel",
    "streamlines",
    "trajectories_3d",
]

#: rcParams every figure is drawn and saved with.
STYLE = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8.5,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.grid": False,
    "legend.frameon": False,
    "svg.fonttype": "path",        # text as outlines: the SVG renders without fonts
    "svg.hashsalt": "sosdyn",      # deterministic element ids in the SVG
    "savefig.facecolor": "white",
}

# Colour-blind safe (Okabe & Ito). Known methods keep a fixed colour; any other name
# takes the unused ones in sorted order (see method_color).
_KNOWN_METHOD_COLORS = {
    "cdsp": "#0072B2",
    "dmp": "#D55E00",
    "clf-dm": "#E69F00",
    "gmr": "#009E73",
    "seds": "#CC79A7",
}
_SPARE_COLORS = ("#56B4E9", "#882255", "#117733", "#999933", "#332288", "#666666", "#CC6677",
                 "#44AA99", "#AA4499", "#DDCC77")

DEMO_COLOR = "#C0282D"        # paper Fig. 1: demonstrations solid red
REPRO_COLOR = "#1F5FBF"       # paper Fig. 1: reproductions dashed blue
STREAM_COLOR = "0.62"         # paper Fig. 1: streamlines gray
GOAL_STYLE = dict(marker="*", markersize=13, color="black", markeredgecolor="white",
                  markeredgewidth=0.8, linestyle="none", zorder=6)

#: Axis labels of the accuracy metrics; ``{u}`` is replaced by the length unit.
METRIC_LABELS = {
    "sea": "SEA ({u}²)",
    "dtwd_total": "DTWD ({u})",
    "dtwd_per_point": "DTWD per point ({u})",
    "vel_rmse": "velocity RMSE ({u}/s)",
    "goal_error": "goal error ({u})",
}


def _styled(func):
    """Draw ``func``'s figure under :data:`STYLE` without touching global rcParams."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with mpl.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def method_color(name: str, methods: Sequence[str] = ()) -> str:
    """Colour of method ``name``; the same in every figure of a report.

    CDSP, DMP, CLF-DM, GMR and SEDS have fixed colours. Any other name gets a spare
    colour by its rank among the unknown names of ``methods`` (sorted), so the figures
    of one report, which share their method list, agree with each other.
    """
    known = _KNOWN_METHOD_COLORS.get(name.lower())
    if known is not None:
        return known
    unknown = sorted({m for m in (*methods, name) if m.lower() not in _KNOWN_METHOD_COLORS})
    return _SPARE_COLORS[unknown.index(name) % len(_SPARE_COLORS)]


def save_figure(fig: Figure, path_without_ext: str | Path, *, dpi: int = 200) -> dict[str, Path]:
    """Write ``fig`` as ``<path>.svg`` and ``<path>.png``; return ``{"svg": .., "png": ..}``.

    Parent folders are created. The SVG carries no date, so re-running an experiment
    with the same data produces the same file.
    """
    base = Path(path_without_ext)
    base.parent.mkdir(parents=True, exist_ok=True)
    paths = {"svg": base.with_name(base.name + ".svg"), "png": base.with_name(base.name + ".png")}
    with mpl.rc_context(STYLE):
        fig.savefig(paths["svg"], format="svg", metadata={"Date": None})
        fig.savefig(paths["png"], format="png", dpi=dpi)
    return paths


# --------------------------------------------------------------------------- helpers

def _new_figure(width: float, height: float) -> Figure:
    return Figure(figsize=(width, height), layout="constrained")


def _as_xy(points) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 2:
        raise ValueError(f"expected an array of shape (T, 2), got {arr.shape}")
    return arr[:, :2]


def _data_bounds(arrays: Sequence[np.ndarray], pad: float = 0.1,
                 square: bool = False) -> tuple[float, float, float, float]:
    """Box around all points, padded by ``pad`` times its larger side on each side.

    ``square=True`` widens the shorter side (about its centre) to the longer one, so an
    equal-aspect axes is filled with data and field instead of white margins.
    """
    pts = np.vstack([a[:, :2] for a in arrays])
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    side = max(float(np.max(hi - lo)), 1e-9)
    half = (np.full(2, side) if square else hi - lo) / 2 + pad * side
    mid = (lo + hi) / 2
    return mid[0] - half[0], mid[0] + half[0], mid[1] - half[1], mid[1] + half[1]


def _frame_state_axes(ax, units: str) -> None:
    """Equal aspect, a full frame and ``x_1``/``x_2`` labels in ``units``."""
    ax.set_aspect("equal", adjustable="box")
    ax.spines[["top", "right"]].set_visible(True)
    ax.set_xlabel(f"$x_1$ ({units})")
    ax.set_ylabel(f"$x_2$ ({units})")


def _mean_std(entry) -> tuple[float, float]:
    """(mean, std) of a metric entry: ``{"mean", "std"}``, a bare number, or missing."""
    if entry is None:
        return np.nan, np.nan
    if isinstance(entry, Mapping):
        mean, std = entry.get("mean"), entry.get("std")
        return (np.nan if mean is None else float(mean)), (0.0 if std is None else float(std))
    return float(entry), 0.0


def _ordered_methods(table: Mapping[str, Mapping[str, object]]) -> list[str]:
    """Methods in order of first appearance over all shapes."""
    return list(dict.fromkeys(m for per_shape in table.values() for m in per_shape))


def _stream_legend_handles() -> list:
    return [
        Line2D([], [], color=STREAM_COLOR, lw=1.0, label="streamlines of the model"),
        Line2D([], [], color=DEMO_COLOR, lw=1.8, label="demonstrations"),
        Line2D([], [], color=REPRO_COLOR, lw=1.8, ls="--", label="reproductions"),
        Line2D([], [], label="goal", **GOAL_STYLE),
    ]


# ----------------------------------------------------------------- state-space plots

@_styled
def streamlines(ax, predict: Callable[[np.ndarray], np.ndarray] | None,
                demos_pos: Sequence[np.ndarray], reproductions: Sequence[np.ndarray],
                goal, bounds: tuple[float, float, float, float] | None = None,
                title: str | None = None, *, units: str = "mm", grid: int = 70,
                density: float = 1.1) -> Figure:
    """Paper Fig. 1: a learned 2-D vector field with the data it was learned from.

    Gray streamlines of ``predict(X) -> Xdot`` on a ``grid`` x ``grid`` lattice over
    ``bounds`` ((xmin, xmax, ymin, ymax); default: the square around demonstrations,
    reproductions and goal, padded by 10 %), the demonstrations as solid red lines,
    the reproductions (rollouts from the demonstrations' starts) as dashed blue lines
    and the goal as a black star. ``predict=None`` (e.g. a time-indexed DMP, which has
    no field) draws the trajectories only.

    With ``ax=None`` a new figure with its legend underneath is returned; with an
    ``ax`` the plot goes there, the caller owns the legend, and ``ax.figure`` is
    returned.
    """
    demos = [_as_xy(d) for d in demos_pos]
    repros = [_as_xy(r) for r in reproductions]
    goal = np.asarray(goal, dtype=float)[:2]
    own_figure = ax is None
    if own_figure:
        fig = _new_figure(4.4, 5.0)
        ax = fig.add_subplot()
    xmin, xmax, ymin, ymax = bounds or _data_bounds([*demos, *repros, goal[None, :]], square=True)

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

    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    _frame_state_axes(ax, units)
    if title:
        ax.set_title(title)
    if own_figure:
        fig.legend(handles=_stream_legend_handles(), loc="outside lower center", ncols=2)
    return ax.figure


@_styled
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
    fig = _new_figure(panel_size * ncols, panel_size * nrows + 0.45)
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
    fig.legend(handles=_stream_legend_handles(), loc="outside lower center", ncols=4)
    return fig


@_styled
def perturbation_trajectories(ax, demo, runs: Mapping[str, np.ndarray],
                              events: Sequence[Mapping] | Mapping[str, Sequence[Mapping]] = (),
                              goal_history=None,
                              title: str | None = None, *, units: str = "mm") -> Figure:
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
    one "goal" star.

    With ``ax=None`` a new figure with the legend underneath is returned, otherwise
    ``ax.figure``.
    """
    own_figure = ax is None
    if own_figure:
        fig = _new_figure(4.6, 5.2)
        ax = fig.add_subplot()
    demo = _as_xy(demo)
    methods = list(runs)
    handles = [Line2D([], [], color="0.75", lw=5, alpha=0.8, solid_capstyle="round",
                      label="demonstration")]
    ax.plot(demo[:, 0], demo[:, 1], color="0.75", lw=5, alpha=0.8, solid_capstyle="round", zorder=1)
    for method, pos in runs.items():
        pos = _as_xy(pos)
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

    all_pts = [demo, *(_as_xy(p) for p in runs.values())]
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

    xmin, xmax, ymin, ymax = _data_bounds(all_pts, pad=0.06, square=True)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    _frame_state_axes(ax, units)
    if title:
        ax.set_title(title)
    if own_figure:
        fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4))
    return ax.figure


@_styled
def trajectories_3d(demos: Sequence[np.ndarray], reproductions: Sequence[np.ndarray], goal,
                    title: str | None = None, *, units: str = "mm") -> Figure:
    """3-D demonstrations (solid red) and reproductions (dashed blue) with the goal.

    The box follows the data ranges (true proportions), except that no side is drawn
    shorter than 35 % of the longest, so a nearly planar motion keeps readable ticks.
    """
    fig = _new_figure(5.4, 5.0)
    ax = fig.add_subplot(projection="3d")
    arrays = [np.asarray(a, dtype=float)[:, :3] for a in (*demos, *reproductions)]
    for d in demos:
        d = np.asarray(d, dtype=float)
        ax.plot(d[:, 0], d[:, 1], d[:, 2], color=DEMO_COLOR, lw=1.5)
    for r in reproductions:
        r = np.asarray(r, dtype=float)
        ax.plot(r[:, 0], r[:, 1], r[:, 2], color=REPRO_COLOR, lw=1.5, ls=(0, (4, 2.5)))
    goal = np.asarray(goal, dtype=float)[:3]
    ax.plot([goal[0]], [goal[1]], [goal[2]], **GOAL_STYLE)
    ranges = np.ptp(np.vstack([*arrays, goal[None, :]]), axis=0)
    ax.set_box_aspect(np.maximum(ranges, 0.35 * ranges.max() + 1e-9), zoom=0.88)
    for axis, name in zip((ax.xaxis, ax.yaxis, ax.zaxis), ("x_1", "x_2", "x_3")):
        axis.set_major_locator(MaxNLocator(4))
        axis.set_label_text(f"${name}$ ({units})")
    if title:
        ax.set_title(title)
    fig.legend(handles=_stream_legend_handles()[1:], loc="outside lower center", ncols=3)
    return fig


# -------------------------------------------------------------------------- bar charts

def _grouped_bars(ax, shapes: Sequence[str], methods: Sequence[str],
                  value: Callable[[str, str], tuple[float, float]],
                  flagged: Callable[[str, str], bool], log: bool | None) -> bool:
    """One group of bars per shape, one bar per method, std as error bars.

    ``value(shape, method)`` gives (mean, std), NaN for "not run" (no bar);
    ``flagged(shape, method)`` hatches the bar. ``log=None`` picks a log axis when
    the positive means span more than two decades. Returns whether the axis is log.
    On a log axis the lower whisker is clipped at 10 % of the mean, since a
    mean - std <= 0 has no place on it.
    """
    stats = np.array([[value(s, m) for m in methods] for s in shapes], dtype=float)
    means, stds = stats[..., 0], stats[..., 1]
    positive = means[np.isfinite(means) & (means > 0)]
    if log is None:
        log = positive.size > 1 and positive.max() / positive.min() > 100
    width = 0.8 / max(len(methods), 1)
    x = np.arange(len(shapes))
    for j, method in enumerate(methods):
        ok = np.isfinite(means[:, j])
        lower = np.minimum(stds[:, j], 0.9 * means[:, j]) if log else stds[:, j]
        bars = ax.bar(x[ok] + (j - (len(methods) - 1) / 2) * width, means[ok, j], width * 0.92,
                      yerr=np.vstack([lower[ok], stds[ok, j]]), color=method_color(method, methods),
                      edgecolor="white", linewidth=0.4, label=method, zorder=2,
                      error_kw=dict(ecolor="0.2", elinewidth=0.8, capsize=1.8, capthick=0.8))
        for bar, shape in zip(bars, np.asarray(shapes)[ok]):
            if flagged(shape, method):
                bar.set_hatch("////")
                bar.set_edgecolor("black")
    if log:
        ax.set_yscale("log")
    ax.set_xticks(x, shapes, rotation=40 if len(shapes) > 5 else 0,
                  ha="right" if len(shapes) > 5 else "center", rotation_mode="anchor")
    ax.set_xlim(-0.6, len(shapes) - 0.4)
    ax.grid(axis="y", color="0.9", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    return log


def _bar_figure(n_shapes: int, n_methods: int, n_rows: int) -> Figure:
    width = float(np.clip(1.6 + n_shapes * (0.22 * n_methods + 0.35), 5.5, 16.0))
    return _new_figure(width, 2.5 * n_rows + 0.9)


@_styled
def accuracy_bars(table: Mapping[str, Mapping[str, Mapping]],
                  metrics: Sequence[str] = ("sea", "dtwd_total"), *,
                  log: bool | None = None, units: str = "mm") -> Figure:
    """Paper Fig. 2: reproduction accuracy per shape and method.

    ``table`` is ``results["accuracy"]`` (shape -> method -> metric -> {mean, std}).
    One panel per metric (stacked, sharing the shape axis); in each, one group of bars
    per shape and one bar per method, with one standard deviation over the
    demonstrations as error bars. ``log``: True/False, or None to choose per panel.
    A method missing for a shape leaves a gap.
    """
    shapes, methods = list(table), _ordered_methods(table)
    fig = _bar_figure(len(shapes), len(methods), len(metrics))
    axes = fig.subplots(len(metrics), 1, sharex=True, squeeze=False)[:, 0]
    for ax, metric in zip(axes, metrics):
        is_log = _grouped_bars(ax, shapes, methods,
                               lambda s, m: _mean_std(table[s].get(m, {}).get(metric)),
                               lambda s, m: False, log)
        label = METRIC_LABELS.get(metric, metric).format(u=units)
        ax.set_ylabel(label + (" [log]" if is_log else ""))
    fig.legend(handles=[Patch(color=method_color(m, methods), label=m) for m in methods],
               loc="outside upper center", ncols=len(methods))
    return fig


@_styled
def robustness_bars(table: Mapping[str, Mapping[str, Mapping]], metric: str = "dtwd_total", *,
                    log: bool | None = None, units: str = "mm") -> Figure:
    """Paper Fig. 3: DTWD to the demonstrations after pushes and after goal changes.

    ``table`` is ``results["robustness"]`` (shape -> method -> {"push", "goal_change"}
    -> {metric: {mean, std}, "converged": fraction}). Top panel: reproductions pushed
    mid-way; bottom panel: goal moved mid-way. Bars are the mean over demonstrations
    with one std; a hatched bar marks a method whose runs did not all converge to the
    (new) goal.
    """
    shapes, methods = list(table), _ordered_methods(table)
    scenarios = [("push", "after pushes"), ("goal_change", "after goal changes")]
    fig = _bar_figure(len(shapes), len(methods), len(scenarios))
    axes = fig.subplots(len(scenarios), 1, sharex=True, squeeze=False)[:, 0]

    def scenario(shape, method, key):
        return table[shape].get(method, {}).get(key) or {}

    any_flag = False
    for ax, (key, label) in zip(axes, scenarios):
        def flagged(s, m, key=key):
            conv = scenario(s, m, key).get("converged")
            return conv is not None and conv < 1.0

        any_flag |= any(flagged(s, m) for s in shapes for m in methods)
        is_log = _grouped_bars(ax, shapes, methods,
                               lambda s, m, key=key: _mean_std(scenario(s, m, key).get(metric)),
                               flagged, log)
        unit_label = METRIC_LABELS.get(metric, metric).format(u=units)
        ax.set_ylabel(f"{unit_label}{' [log]' if is_log else ''}")
        ax.set_title(label, loc="left")
    handles = [Patch(color=method_color(m, methods), label=m) for m in methods]
    if any_flag:
        handles.append(Patch(facecolor="white", edgecolor="black", hatch="////",
                             label="not all runs converged"))
    fig.legend(handles=handles, loc="outside upper center", ncols=len(handles))
    return fig


# ----------------------------------------------------------------------- benchmarks

def _plain_log_ticks(axis, limits: tuple[float, float]) -> None:
    """Log-axis labels as plain numbers ("20", "0.5"); on a span under two decades the
    minor ticks at 2x and 5x are labelled too, so short axes are not left bare."""
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    short = np.log10(limits[1] / limits[0]) < 2

    def minor(v, _):
        mantissa = round(v / 10 ** np.floor(np.log10(v)), 6)
        return f"{v:g}" if short and mantissa in (2.0, 5.0) else ""

    axis.set_minor_formatter(FuncFormatter(minor))


@_styled
def scaling_plot(series: Mapping[str, Mapping[str, Sequence[float]]], *,
                 xlabel: str = "problem size", ylabel: str = "time (s)",
                 title: str | None = None) -> Figure:
    """Log-log scaling of a cost (e.g. solve time) against a size (e.g. degree, #monomials).

    ``series``: name -> {"x": sizes, "y": values, optional "std"}. Each series is a
    line with markers in its method/solver colour; with three or more points its
    least-squares slope in log-log space is shown in the legend (the empirical
    exponent).
    """
    fig = _new_figure(5.2, 3.8)
    ax = fig.add_subplot()
    names = list(series)
    for name, s in series.items():
        x, y = np.asarray(s["x"], dtype=float), np.asarray(s["y"], dtype=float)
        ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
        label = name
        if ok.sum() >= 3:
            slope = np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0]
            label = f"{name} (slope {slope:.2f})"
        std = s.get("std")
        ax.errorbar(x[ok], y[ok], yerr=None if std is None else np.asarray(std, dtype=float)[ok],
                    color=method_color(name, names), marker="o", markersize=4, lw=1.4,
                    capsize=2, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        _plain_log_ticks(axis, lim)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(which="major", color="0.88", lw=0.6)
    ax.grid(which="minor", color="0.95", lw=0.4)
    if title:
        ax.set_title(title)
    fig.legend(loc="outside lower center", ncols=min(len(names), 3))
    return fig

"""Point-and-interval charts of the results tables (accuracy, robustness) and log-log scaling plots."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, NullFormatter

from .style import METRIC_LABELS, median_iqr, method_color, new_figure, ordered_methods, styled

#: Most legend entries in one row; longer legends wrap instead of running off the figure.
LEGEND_COLUMNS = 4


def _interval_points(ax, shapes: Sequence[str], methods: Sequence[str],
                     value: Callable[[str, str], tuple[float, float, float]],
                     flagged: Callable[[str, str], bool], log: bool | None) -> bool:
    """One group per shape, one point per method: the median with the interquartile range.

    ``value(shape, method)`` gives (median, q1, q3), NaN for "not run" (no point);
    ``flagged(shape, method)`` draws the point hollow. Since q1 <= median <= q3 and the
    metrics are non-negative, no whisker crosses zero. ``log=None`` picks a log axis when
    the positive medians span more than two decades. Returns whether the axis is log.
    """
    stats = np.array([[value(s, m) for m in methods] for s in shapes], dtype=float)
    med, q1, q3 = stats[..., 0], stats[..., 1], stats[..., 2]
    positive = med[np.isfinite(med) & (med > 0)]
    if log is None:
        log = positive.size > 1 and positive.max() / positive.min() > 100
    width = 0.8 / max(len(methods), 1)
    x = np.arange(len(shapes))
    for j, method in enumerate(methods):
        color = method_color(method, methods)
        for i, shape in enumerate(shapes):
            if not np.isfinite(med[i, j]):
                continue
            hollow = flagged(shape, method)
            ax.errorbar(x[i] + (j - (len(methods) - 1) / 2) * width, med[i, j],
                        yerr=[[med[i, j] - q1[i, j]], [q3[i, j] - med[i, j]]], fmt="o",
                        color=color, markersize=4.5, markerfacecolor="white" if hollow else color,
                        markeredgewidth=1.1, elinewidth=1.3, capsize=2, capthick=1.0, zorder=3,
                        label=method)
    if log:
        ax.set_yscale("log")
    else:
        ax.set_ylim(bottom=0)
    for k in range(1, len(shapes)):
        ax.axvline(k - 0.5, color="0.88", lw=0.6, zorder=0)
    ax.set_xticks(x, shapes, rotation=40 if len(shapes) > 5 else 0,
                  ha="right" if len(shapes) > 5 else "center", rotation_mode="anchor")
    ax.set_xlim(-0.5, len(shapes) - 0.5)
    ax.grid(axis="y", color="0.92", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    return log


def _method_handles(methods: Sequence[str]) -> list:
    return [Line2D([], [], color=method_color(m, methods), marker="o", markersize=4.5, lw=1.3,
                   label=m) for m in methods]


def _interval_figure(n_shapes: int, n_methods: int, n_rows: int, n_legend: int) -> Figure:
    width = float(np.clip(1.6 + n_shapes * (0.22 * n_methods + 0.35), 6.0, 16.0))
    legend_rows = -(-n_legend // LEGEND_COLUMNS)
    return new_figure(width, 2.5 * n_rows + 0.5 + 0.25 * legend_rows)


@styled
def accuracy_bars(table: Mapping[str, Mapping[str, Mapping]],
                  metrics: Sequence[str] = ("sea", "dtwd_total"), *,
                  log: bool | None = None, units: str = "mm") -> Figure:
    """Paper Fig. 2: reproduction accuracy per shape and method, as points with intervals.

    ``table`` is ``results["accuracy"]`` (shape -> method -> metric -> {mean, std,
    per_demo}). One panel per metric (stacked, sharing the shape axis); in each, one
    group per shape and one point per method: the median over the demonstrations with
    the interquartile range (:func:`~.style.median_iqr`). ``log``: True/False, or None to
    choose per panel. A method missing for a shape leaves a gap.
    """
    shapes, methods = list(table), ordered_methods(table)
    fig = _interval_figure(len(shapes), len(methods), len(metrics), len(methods))
    axes = fig.subplots(len(metrics), 1, sharex=True, squeeze=False)[:, 0]
    for ax, metric in zip(axes, metrics):
        def value(s, m, metric=metric):
            return median_iqr(table[s].get(m, {}).get(metric))

        is_log = _interval_points(ax, shapes, methods, value, lambda s, m: False, log)
        label = METRIC_LABELS.get(metric, metric).format(u=units)
        ax.set_ylabel(label + (" [log]" if is_log else ""))
    fig.legend(handles=_method_handles(methods), loc="outside upper center",
               ncols=min(len(methods), LEGEND_COLUMNS))
    return fig


@styled
def robustness_bars(table: Mapping[str, Mapping[str, Mapping]], metric: str = "dtwd_total", *,
                    log: bool | None = None, units: str = "mm") -> Figure:
    """Paper Fig. 3: DTWD to the demonstrations after pushes and after goal changes.

    ``table`` is ``results["robustness"]`` (shape -> method -> {"push", "goal_change"}
    -> {metric: {mean, std, per_demo}, "converged": fraction}). Top panel: reproductions
    pushed mid-way; bottom panel: goal moved mid-way. Each point is the median over the
    demonstrations with the interquartile range; a hollow point marks a method whose runs
    did not all converge to the (new) goal.
    """
    shapes, methods = list(table), ordered_methods(table)
    scenarios = [("push", "after pushes"), ("goal_change", "after goal changes")]

    def scenario(shape, method, key):
        return table[shape].get(method, {}).get(key) or {}

    def flagged(s, m, key):
        conv = scenario(s, m, key).get("converged")
        return conv is not None and conv < 1.0

    any_flag = any(flagged(s, m, k) for s in shapes for m in methods for k, _ in scenarios)
    fig = _interval_figure(len(shapes), len(methods), len(scenarios), len(methods) + any_flag)
    axes = fig.subplots(len(scenarios), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (key, label) in zip(axes, scenarios):
        is_log = _interval_points(ax, shapes, methods,
                                  lambda s, m, key=key: median_iqr(scenario(s, m, key).get(metric)),
                                  lambda s, m, key=key: flagged(s, m, key), log)
        unit_label = METRIC_LABELS.get(metric, metric).format(u=units)
        ax.set_ylabel(f"{unit_label}{' [log]' if is_log else ''}")
        ax.set_title(label, loc="left")
    handles = _method_handles(methods)
    if any_flag:
        handles.append(Line2D([], [], color="0.3", marker="o", markersize=4.5, lw=1.3,
                              markerfacecolor="white", label="not all runs converged"))
    fig.legend(handles=handles, loc="outside upper center", ncols=min(len(handles), LEGEND_COLUMNS))
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


@styled
def scaling_plot(series: Mapping[str, Mapping[str, Sequence[float]]], *,
                 xlabel: str = "problem size", ylabel: str = "time (s)",
                 title: str | None = None) -> Figure:
    """Log-log scaling of a cost (e.g. solve time) against a size (e.g. degree, #monomials).

    ``series``: name -> {"x": sizes, "y": values, optional "std"}. Each series is a
    line with markers in its method/solver colour; with three or more points its
    least-squares slope in log-log space is shown in the legend (the empirical
    exponent).
    """
    fig = new_figure(5.2, 3.8)
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
    sizes = np.unique(np.concatenate([np.asarray(s["x"], dtype=float) for s in series.values()]))
    if 0 < sizes.size <= 10 and np.all(sizes > 0) and np.all(sizes == np.round(sizes)):
        ax.set_xticks(sizes, [f"{v:g}" for v in sizes])     # few integer sizes (n = 2..7): label each
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(which="major", color="0.88", lw=0.6)
    ax.grid(which="minor", color="0.95", lw=0.4)
    if title:
        ax.set_title(title)
    fig.legend(loc="outside lower center", ncols=min(len(names), 3))
    return fig

"""Bar charts of the results tables (accuracy, robustness) and log-log scaling plots."""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter

from .style import METRIC_LABELS, mean_std, method_color, new_figure, ordered_methods, styled


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
    return new_figure(width, 2.5 * n_rows + 0.9)


@styled
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
    shapes, methods = list(table), ordered_methods(table)
    fig = _bar_figure(len(shapes), len(methods), len(metrics))
    axes = fig.subplots(len(metrics), 1, sharex=True, squeeze=False)[:, 0]
    for ax, metric in zip(axes, metrics):
        is_log = _grouped_bars(ax, shapes, methods,
                               lambda s, m: mean_std(table[s].get(m, {}).get(metric)),
                               lambda s, m: False, log)
        label = METRIC_LABELS.get(metric, metric).format(u=units)
        ax.set_ylabel(label + (" [log]" if is_log else ""))
    fig.legend(handles=[Patch(color=method_color(m, methods), label=m) for m in methods],
               loc="outside upper center", ncols=len(methods))
    return fig


@styled
def robustness_bars(table: Mapping[str, Mapping[str, Mapping]], metric: str = "dtwd_total", *,
                    log: bool | None = None, units: str = "mm") -> Figure:
    """Paper Fig. 3: DTWD to the demonstrations after pushes and after goal changes.

    ``table`` is ``results["robustness"]`` (shape -> method -> {"push", "goal_change"}
    -> {metric: {mean, std}, "converged": fraction}). Top panel: reproductions pushed
    mid-way; bottom panel: goal moved mid-way. Bars are the mean over demonstrations
    with one std; a hatched bar marks a method whose runs did not all converge to the
    (new) goal.
    """
    shapes, methods = list(table), ordered_methods(table)
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
                               lambda s, m, key=key: mean_std(scenario(s, m, key).get(metric)),
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
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(which="major", color="0.88", lw=0.6)
    ax.grid(which="minor", color="0.95", lw=0.4)
    if title:
        ax.set_title(title)
    fig.legend(loc="outside lower center", ncols=min(len(names), 3))
    return fig

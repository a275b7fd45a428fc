"""Shared style of the report figures: rcParams, method colours, saving, data boxes.

Every function takes plain data (arrays, callables, dicts shaped like the results
schema in :mod:`sosdyn.report.html`) and returns a :class:`matplotlib.figure.Figure`;
:func:`save_figure` writes it as SVG and PNG. Figures are built on
``matplotlib.figure.Figure`` directly, so nothing is registered with pyplot, nothing
leaks between calls and no GUI backend is ever needed.

Conventions shared by all figures:

* each method has one colour everywhere (:func:`method_color`, :data:`METHOD_COLORS`), so
  CDSP is the same blue in the bar charts, the perturbation plots and the scaling plots;
* 2-D state-space plots use an equal aspect ratio and axes labelled in ``units``;
* legends sit outside the data (under or above the axes), never on top of it;
* layout is matplotlib's constrained layout.
"""
from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

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

#: The one home of the method colours (every figure calls :func:`method_color`): one hue per
#: method, colour-blind safe -- Okabe & Ito's blue and vermillion with Paul Tol's teal, indigo,
#: magenta, green and yellow, and black. Pairwise CIELAB distance >= 33 for normal vision and
#: >= 17 under simulated deuteranopia and protanopia (Machado et al. 2009; checked in
#: tests/report/test_figures.py). Keys are lower-case method names.
METHOD_COLORS = {
    "cdsp": "#0072B2",          # blue: the default CDSP()
    "cdsp-ica": "#009988",      # teal
    "cdsp-cubic": "#332288",    # indigo
    "cdsp (paper)": "#000000",  # black
    "seds-like": "#EE3377",     # magenta
    "gmr": "#117733",           # green
    "dmp": "#D55E00",           # vermillion
    "clf-dm": "#CCBB44",        # yellow
}
METHOD_COLORS["seds"] = METHOD_COLORS["seds-like"]
#: Colours of other names (variants, solvers), taken in sorted-name order (see method_color).
_SPARE_COLORS = ("#56B4E9", "#882255", "#E69F00", "#999933", "#CC79A7", "#777777", "#44AA99",
                 "#AA4499", "#DDCC77", "#CC6677")

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


def styled(func):
    """Draw ``func``'s figure under :data:`STYLE` without touching global rcParams."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with mpl.rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def method_color(name: str, methods: Sequence[str] = ()) -> str:
    """Colour of method ``name``; the same in every figure of a report.

    The methods of :data:`METHOD_COLORS` have fixed colours. Any other name gets a spare
    colour by its rank among the unknown names of ``methods`` (sorted), so the figures
    of one report, which share their method list, agree with each other.
    """
    known = METHOD_COLORS.get(name.lower())
    if known is not None:
        return known
    unknown = sorted({m for m in (*methods, name) if m.lower() not in METHOD_COLORS})
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

def new_figure(width: float, height: float) -> Figure:
    return Figure(figsize=(width, height), layout="constrained")


def as_xy(points) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 2:
        raise ValueError(f"expected an array of shape (T, 2), got {arr.shape}")
    return arr[:, :2]


def data_bounds(arrays: Sequence[np.ndarray], pad: float = 0.1,
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


def axis_label(i: int, units: str, names=None) -> str:
    """The label of coordinate i: its name (the data's column; default $x_{i+1}$) and the units."""
    k = i + 1
    name = names[i] if names is not None else f"$x_{k}$" if k < 10 else f"$x_{{{k}}}$"
    return f"{name} ({units})" if units else name


def frame_state_axes(ax, units: str, names=None) -> None:
    """Equal aspect, a full frame and the first two coordinates' labels (:func:`axis_label`)."""
    ax.set_aspect("equal", adjustable="box")
    ax.spines[["top", "right"]].set_visible(True)
    ax.set_xlabel(axis_label(0, units, names))
    ax.set_ylabel(axis_label(1, units, names))


def finish_state_axes(ax, bounds, units: str, title: str | None, legend_handles=None, ncols: int = 2, names=None):
    """Limits ``bounds`` (xmin, xmax, ymin, ymax), the state frame, a title, and -- for a
    figure of its own (``legend_handles`` given) -- a legend below the axes; returns the figure."""
    xmin, xmax, ymin, ymax = bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    frame_state_axes(ax, units, names)
    if title:
        ax.set_title(title)
    if legend_handles is not None:
        ax.figure.legend(handles=legend_handles, loc="outside lower center", ncols=ncols)
    return ax.figure


def median_iqr(entry) -> tuple[float, float, float]:
    """(median, first quartile, third quartile) of a metric entry over its demonstrations.

    ``{"per_demo": [...]}`` gives the sample quantiles (NaN values ignored); an entry
    without ``per_demo`` (``{"mean"}`` or a bare number) gives its value three times (no
    spread); a missing entry gives NaNs ("not run").
    """
    if entry is None:
        return np.nan, np.nan, np.nan
    if isinstance(entry, Mapping):
        values = np.asarray(entry.get("per_demo") or [], dtype=float)
        values = values[np.isfinite(values)]
        if values.size:
            q1, med, q3 = np.percentile(values, [25, 50, 75])
            return float(med), float(q1), float(q3)
        mean = entry.get("mean")
        value = np.nan if mean is None else float(mean)
    else:
        value = float(entry)
    return value, value, value


def ordered_methods(table: Mapping[str, Mapping[str, object]]) -> list[str]:
    """Methods in order of first appearance over all shapes."""
    return list(dict.fromkeys(m for per_shape in table.values() for m in per_shape))


def stream_legend_handles(demos: bool = True, streams: bool = True) -> list:
    """Legend entries of the state-space plots; ``demos=False`` / ``streams=False`` leave out the
    demonstrations / the streamlines (a plot without them lists only what it shows)."""
    return [
        *([Line2D([], [], color=STREAM_COLOR, lw=1.0, label="streamlines of the model")] if streams else []),
        *([Line2D([], [], color=DEMO_COLOR, lw=1.8, label="demonstrations")] if demos else []),
        Line2D([], [], color=REPRO_COLOR, lw=1.8, ls="--", label="reproductions"),
        Line2D([], [], label="goal", **GOAL_STYLE),
    ]


# ----------------------------------------------------------------- state-space plots

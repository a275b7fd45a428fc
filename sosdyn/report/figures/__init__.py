"""Publication figures for sosdyn reports (matplotlib, no pyplot state).

``style`` holds what every figure shares (rcParams, method colours, saving, data boxes);
``streamlines``, ``trajectories``, ``poses`` and ``bars`` draw the figures; ``models`` draws any
fitted model (``sosdyn plot``). See :mod:`.style` for the conventions.
"""
from .bars import accuracy_bars, robustness_bars, scaling_plot
from .models import model_figure
from .streamlines import streamline_panel, streamlines
from .style import (GOAL_STYLE, METHOD_COLORS, METRIC_LABELS, STYLE, data_bounds, median_iqr, method_color,
                    save_figure)
from .trajectories import perturbation_trajectories, time_series, trajectories_3d

__all__ = [
    "GOAL_STYLE",
    "METHOD_COLORS",
    "METRIC_LABELS",
    "STYLE",
    "accuracy_bars",
    "data_bounds",
    "median_iqr",
    "model_figure",
    "method_color",
    "perturbation_trajectories",
    "robustness_bars",
    "save_figure",
    "scaling_plot",
    "streamline_panel",
    "streamlines",
    "time_series",
    "trajectories_3d",
]

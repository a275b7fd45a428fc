"""Reports of sosdyn experiments: publication figures, an HTML page and its PDF.

``figures`` draws from plain data (arrays, callables, dicts); ``html`` renders a results
dict (schema in :mod:`sosdyn.report.html`) into a self-contained ``index.html`` and a PDF.
"""

from .figures import (
    accuracy_bars,
    method_color,
    perturbation_trajectories,
    robustness_bars,
    save_figure,
    scaling_plot,
    streamline_panel,
    streamlines,
    trajectories_3d,
)
from .html import build_report, load_results, render_html, render_pdf

__all__ = [
    "accuracy_bars",
    "build_report",
    "load_results",
    "method_color",
    "perturbation_trajectories",
    "render_html",
    "render_pdf",
    "robustness_bars",
    "save_figure",
    "scaling_plot",
    "streamline_panel",
    "streamlines",
    "trajectories_3d",
]

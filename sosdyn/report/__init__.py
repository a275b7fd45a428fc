"""Reports of sosdyn experiments: publication figures, an HTML page and its PDF.

``figures`` draws from plain data (arrays, callables, dicts); ``html`` renders a results
dict (schema in :mod:`sosdyn.report.html`) into a self-contained ``index.html`` and a PDF.
"""

from . import figures
from .html import build_report, load_results, render_html, render_pdf

__all__ = ["figures", "build_report", "load_results", "render_html", "render_pdf"]

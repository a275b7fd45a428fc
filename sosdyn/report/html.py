"""The experiment report: one self-contained HTML page and the same page as PDF.

:func:`render_html` turns a *results dict* into ``out_dir/index.html`` (figures are
embedded as data URIs, so the file can be mailed or opened from anywhere);
:func:`render_pdf` prints that page with WeasyPrint; :func:`build_report` does both
from a ``results.json``.

Results schema
--------------
Every key is optional: a missing (or unreadable) section is shown as "not run".
A results *file* (:func:`load_results`) must hold ``meta`` and ``findings`` and no keys but
those below, each a JSON value of the listed kind or null (so a model file or ``{}`` is refused).
Lengths are in the demonstrations' unit (mm for LASA), times in seconds. A *stat* is
``{"mean": float, "std": float, "per_demo": [float, ...]}`` (``per_demo`` optional).

.. code-block:: text

    {"meta": {"sosdyn_version", "git_commit", "created", "python", "platform",
              "packages": {name: version}, "seed", "command"},
     "pages": [{"title": str, "href": str | null, "finding": str, "numbers": {label: value},
                "data": str | null, "command": str}],
     "findings": [{"title": str, "text": str (markup subset), "numbers": {label: value}}],
     "methods": {method: {"description": str, "settings": {name: value}}},
     "accuracy": {shape: {method: {
         "sea": stat, "dtwd_total": stat, "dtwd_per_point": stat,
         "vel_rmse": float, "goal_error": stat,
         "grid_convergence": float | null,      # fraction of grid starts reaching the goal
         "n_points": int, "fit_time_s": float, "certified": bool | null}}},
     "robustness": {shape: {method: {
         "push":        {"dtwd_total": stat, "goal_error": stat, "converged": float},
         "goal_change": {"dtwd_total": stat, "goal_error": stat, "converged": float}}}},
     "certificates": {shape: {method: {
         "min_gram_eig", "max_coeff_residual", "max_sampled_eig", "n_samples",
         "passed": bool, "metric_collapse": {label: value} | null}}},
     "timings": {shape: {method: {"em_s", "build_s", "solve_s", "verify_s", "total_s"}}},
     "diagnostics": {shape: {method: {"final_cost", "history": [{"step", "cost", "margin"}]}
                                     | {"error": str}}},
     "figures": {name: {"svg": path, "png": path, "caption": str}}}

``pages`` is the index of the reports (shown first, one row per page: a link to it, relative to
the report folder, or none for a page not built yet; its one-line finding, plain text, with the
values it quotes in ``numbers``; the data file it was read from; the command that builds it).
``diagnostics`` is what the findings are computed from beside the tables; it is not shown.
A stat whose ``per_demo`` holds non-finite values (failed runs) is shown as the mean ± std of
the finite ones and "k of n failed".

Figure paths are relative to ``base_dir`` (for :func:`build_report`: the folder of
``results.json``); SVG is embedded when present and below 2 MB, PNG otherwise.
Unless rendered with ``trusted=True`` (the experiments' own results), a figure path that
leads outside ``base_dir`` (``..``, an absolute path, a symlink out) is refused.
``findings[*].text`` may use a small markup subset (:func:`markup`: ``<b>``, ``<i>``,
``<br>`` and character entities); anything else in it is escaped. ``findings[*].numbers``
whose labels read ``"<shape>: <quantity>"`` are shown as one table (a row per shape, a column
per quantity), the others as labelled values. Benchmarks have their own page
(:mod:`sosdyn.report.bench`). A figure file over ``max_file_bytes`` (:mod:`sosdyn.limits`) is
refused before it is read. ``index.html`` and ``report.pdf`` are written atomically
(:func:`sosdyn.files.replace_atomically`): a failed write leaves the previous report whole, and a
symlink in their place is replaced, never followed.
"""

from __future__ import annotations

import base64
import math
import re
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path

import jinja2
import numpy as np
from markupsafe import Markup, escape

from ..errors import InputError, SosdynError
from ..files import replace_atomically
from ..limits import format_bytes, get_limits, raise_hint
from .results import check_results, load_results

__all__ = ["REPORT_FILES", "build_report", "check_results", "load_results", "render_html", "render_pdf"]

REPORT_FILES = {"html": "index.html", "pdf": "report.pdf"}     # written into the output folder
BENCH_PAGE = "bench/index.html"   # the benchmark report (sosdyn.report.bench), linked when present

_MAX_INLINE_SVG = 2_000_000      # bytes; larger SVGs (dense streamplots) go in as PNG
_MIME_TYPES = {"svg": "image/svg+xml", "png": "image/png"}      # in order of preference

# (key, column header, better) for the accuracy table; better: "low", "high" or None.
_ACCURACY_COLUMNS = (
    ("sea", "SEA (mm²)", "low"),
    ("dtwd_total", "DTWD total (mm)", "low"),
    ("dtwd_per_point", "DTWD / point (mm)", "low"),
    ("vel_rmse", "vel. RMSE (mm/s)", "low"),
    ("goal_error", "goal error (mm)", "low"),
    ("grid_convergence", "grid conv.", "high"),
    ("n_points", "points", None),
    ("fit_time_s", "fit (s)", None),
    ("certified", "certified", None),
)
_SCENARIOS = (("push", "after pushes"), ("goal_change", "after goal changes"))
_SCENARIO_COLUMNS = (("dtwd_total", "DTWD (mm)"), ("goal_error", "goal error (mm)"),
                     ("converged", "converged"))
_CERTIFICATE_COLUMNS = (("min_gram_eig", "min Gram eig."), ("max_coeff_residual", "max coeff. residual"),
                        ("max_sampled_eig", "max sampled eig."), ("n_samples", "samples"))
_TIMING_COLUMNS = (("em_s", "EM"), ("build_s", "build"), ("solve_s", "solve"),
                   ("verify_s", "verify"), ("total_s", "total"))


# ----------------------------------------------------------------------- formatting

def fmt(value, digits: int = 3) -> str:
    """A table cell: ``digits`` significant digits, scientific outside [1e-3, 1e5),
    "—" for None."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "∞" if value > 0 else "−∞"
        size = abs(value)
        if size == 0:
            return "0"
        if 1e-3 <= size < 1e5:
            return f"{value:.{max(0, digits - 1 - math.floor(math.log10(size)))}f}"
        return f"{value:.{digits - 1}e}"
    if isinstance(value, Mapping):
        return "; ".join(f"{k}: {fmt(v)}" for k, v in value.items())
    return str(value)


def _mean(entry) -> float | None:
    """Mean of a stat dict or a bare number; None when absent."""
    value = entry.get("mean") if isinstance(entry, Mapping) else entry
    return None if value is None or isinstance(value, bool) else float(value)


def _finite(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _stat_text(entry) -> str:
    """"mean ± std"; with failed runs (non-finite per-demo values) the mean ± std of the others
    and "k of n failed", never "∞ ± ∞"."""
    if not isinstance(entry, Mapping):
        return fmt(entry)
    per_demo = entry.get("per_demo") or []
    failed = sum(not _finite(v) for v in per_demo)
    if failed or (entry.get("mean") is not None and not _finite(entry.get("mean"))):
        done = [float(v) for v in per_demo if _finite(v)]
        if not done:
            return f"all {len(per_demo)} failed" if per_demo else "failed"
        return (f"{fmt(float(np.mean(done)))} ± {fmt(float(np.std(done)), digits=2)} "
                f"({failed} of {len(per_demo)} failed)")
    if entry.get("std") is None:
        return fmt(entry.get("mean"))
    return f"{fmt(entry.get('mean'))} ± {fmt(entry.get('std'), digits=2)}"


def _percent(value) -> str:
    return "—" if value is None else f"{100 * float(value):.0f} %"


def _pairs(section: Mapping) -> list[tuple[str, str, Mapping]]:
    """(shape, method, entry) triples of a shape -> method -> entry section."""
    return [(shape, method, entry or {}) for shape, per_method in section.items()
            for method, entry in (per_method or {}).items()]


def _group_rows(rows: list[dict]) -> list[dict]:
    """Mark the first row of each shape (``first``): it starts a visual group.

    The shape is repeated on every row (muted after the first) rather than spanned, so a
    page break inside a group still shows which shape a row belongs to.
    """
    for i, row in enumerate(rows):
        row["first"] = i == 0 or rows[i - 1]["shape"] != row["shape"]
    return rows


# ------------------------------------------------------------------ section builders

def _accuracy(section: Mapping) -> dict:
    triples = _pairs(section)
    best: dict[tuple[str, str], float] = {}
    for key, _, better in _ACCURACY_COLUMNS:
        if better is None:
            continue
        for shape in section:
            means = [m for s, _, e in triples if s == shape and (m := _mean(e.get(key))) is not None
                     and math.isfinite(m)]
            if len(means) > 1:
                best[shape, key] = min(means) if better == "low" else max(means)
    rows = []
    for shape, method, entry in triples:
        cells = []
        for key, _, better in _ACCURACY_COLUMNS:
            value = entry.get(key)
            if key == "certified":
                text = {True: "✓", False: "✗ failed", None: "n/a"}[value]
            elif key == "grid_convergence":
                text = _percent(value)
            else:
                text = _stat_text(value)
            cells.append({"text": text, "best": better is not None
                          and best.get((shape, key)) == _mean(value)})
        rows.append({"shape": shape, "method": method, "cells": cells})
    return {"headers": [h for _, h, _ in _ACCURACY_COLUMNS], "rows": _group_rows(rows)}


def _robustness(section: Mapping) -> dict:
    rows = []
    for shape, method, entry in _pairs(section):
        cells = []
        for scenario, _ in _SCENARIOS:
            part = entry.get(scenario) or {}
            for key, _ in _SCENARIO_COLUMNS:
                value = part.get(key)
                cells.append({"text": _percent(value) if key == "converged" else _stat_text(value),
                              "warn": key == "converged" and value is not None and value < 1.0})
        rows.append({"shape": shape, "method": method, "cells": cells})
    return {"scenarios": [label for _, label in _SCENARIOS],
            "headers": [h for _, h in _SCENARIO_COLUMNS], "rows": _group_rows(rows)}


def _certificates(section: Mapping) -> dict:
    rows = [{"shape": shape, "method": method,
             "cells": [fmt(entry.get(key)) for key, _ in _CERTIFICATE_COLUMNS],
             "passed": entry.get("passed"),
             "collapse": fmt(entry.get("metric_collapse"))}
            for shape, method, entry in _pairs(section)]
    return {"headers": [h for _, h in _CERTIFICATE_COLUMNS], "rows": _group_rows(rows)}


def _timings(section: Mapping) -> dict:
    triples = _pairs(section)
    rows = [{"shape": shape, "method": method, "cells": [fmt(entry.get(key)) for key, _ in _TIMING_COLUMNS]}
            for shape, method, entry in triples]
    total = sum(float(e.get("total_s") or 0.0) for _, _, e in triples)
    return {"headers": [f"{h} (s)" for _, h in _TIMING_COLUMNS], "rows": _group_rows(rows),
            "total": fmt(total)}


def _methods(section: Mapping) -> list[dict]:
    return [{"name": name, "description": (spec or {}).get("description", ""),
             "settings": [(k, fmt(v)) for k, v in ((spec or {}).get("settings") or {}).items()]}
            for name, spec in section.items()]


_ALLOWED_TAG = re.compile(r"&lt;(/?(?:b|i)|br)&gt;")
_ALLOWED_ENTITY = re.compile(r"&amp;(#[0-9]{1,7}|#x[0-9a-fA-F]{1,6}|[a-zA-Z][a-zA-Z0-9]{1,31});")


def markup(text: str) -> Markup:
    """``text`` as HTML: everything escaped except ``<b>``, ``</b>``, ``<i>``, ``</i>``,
    ``<br>`` and character entities (``&gt;``, ``&#8804;``), the findings' subset."""
    escaped = str(escape(text))
    escaped = _ALLOWED_TAG.sub(r"<\1>", escaped)
    return Markup(_ALLOWED_ENTITY.sub(r"&\1;", escaped))


def number_table(numbers: Mapping) -> tuple[dict | None, list[tuple[str, str]]]:
    """Split a finding's numbers: labels ``"<row>: <column>"`` as a table ``{"columns",
    "rows": [(row, [cell, ...])]}`` (None when there are none; "—" for a missing pair),
    the other labels as ``[(label, text)]``."""
    cells, other = {}, []
    for label, value in numbers.items():
        row, sep, column = str(label).partition(": ")
        if sep:
            cells[row, column] = fmt(value)
        else:
            other.append((label, fmt(value)))
    if not cells:
        return None, other
    rows = list(dict.fromkeys(r for r, _ in cells))
    columns = list(dict.fromkeys(c for _, c in cells))
    return ({"columns": columns, "rows": [(r, [cells.get((r, c), "—") for c in columns]) for r in rows]},
            other)


def _findings(section) -> list[dict]:
    out = []
    for f in section:
        table, other = number_table(f.get("numbers") or {})
        out.append({"title": f.get("title", ""), "text": markup(str(f.get("text", ""))),
                    "table": table, "numbers": other})
    return out


def _environment(meta: Mapping) -> dict:
    return {"rows": [(k, fmt(v)) for k, v in meta.items() if k != "packages"],
            "packages": sorted((k, str(v)) for k, v in (meta.get("packages") or {}).items())}


def markdown_html(text: str) -> str:
    """Markdown to HTML with markdown-it (installed with rich); <pre> without it."""
    try:
        from markdown_it import MarkdownIt
    except ImportError:
        return f"<pre>{escape(text)}</pre>"
    return MarkdownIt("commonmark", {"html": False}).enable("table").render(text)


def _inside(path: Path, folder: Path) -> bool:
    """Does ``path`` (symlinks resolved) lie in ``folder``?"""
    return path.resolve().is_relative_to(folder.resolve())


def _check_figure_size(name: str, path: Path) -> None:
    """InputError if the figure file is over ``max_file_bytes`` (checked before it is read)."""
    size, limit = path.stat().st_size, get_limits().max_file_bytes
    if size > limit:
        raise InputError(f"figure {name!r}: {path} is {format_bytes(size)}, over max_file_bytes = "
                         f"{format_bytes(limit)}; a report embeds its figures whole. Try: a smaller figure "
                         f"(a lower dpi), or if it is meant to be embedded raise the limit with {raise_hint('max_file_bytes')}.")


def _figures(section: Mapping, base_dir: Path, trusted: bool = False) -> list[dict]:
    """Each figure as a data URI: the SVG unless it is over the size limit and a PNG exists.
    Untrusted results: InputError for a path outside ``base_dir``, before any file is read."""
    figures = []
    for name, spec in section.items():
        spec = spec or {}
        given = {kind: base_dir / spec[kind] for kind in _MIME_TYPES if spec.get(kind)}
        outside = [str(spec[kind]) for kind, path in given.items() if not (trusted or _inside(path, base_dir))]
        if outside:
            raise InputError(f"figure {name!r}: {', '.join(outside)} lies outside the report folder "
                             f"{base_dir}; a results file may only embed figures below its own folder. "
                             "Try: move the figures next to the results file and give relative paths.")
        found = {kind: path for kind, path in given.items() if path.is_file()}
        if "svg" in found and "png" in found and found["svg"].stat().st_size > _MAX_INLINE_SVG:
            del found["svg"]
        src = None
        if found:
            kind, path = next(iter(found.items()))
            _check_figure_size(name, path)
            src = f"data:{_MIME_TYPES[kind]};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"
        missing = ", ".join(str(spec[kind]) for kind in given) or "no file given"
        figures.append({"name": name, "caption": spec.get("caption", name), "src": src,
                        "missing": None if src else missing})
    return figures


def _pages(section) -> list[dict]:
    return [{"title": str(p.get("title", "")), "href": p.get("href"), "finding": str(p.get("finding") or ""),
             "data": p.get("data"), "command": p.get("command")} for p in section]


_SECTIONS: dict[str, Callable] = {
    "pages": _pages, "findings": _findings, "methods": _methods, "accuracy": _accuracy,
    "robustness": _robustness, "certificates": _certificates, "timings": _timings,
    "meta": _environment,
}
# --------------------------------------------------------------------------- public

def jinja_environment() -> jinja2.Environment:
    """The report templates (``sosdyn/report/templates``), autoescaped, with the ``fmt`` filter."""
    env = jinja2.Environment(loader=jinja2.PackageLoader("sosdyn.report", "templates"),
                             autoescape=True, trim_blocks=True, lstrip_blocks=True)
    env.filters["fmt"] = fmt
    return env


def report_css() -> str:
    """The reports' stylesheet (``templates/report.css``), for pages built outside the template."""
    return jinja_environment().loader.get_source(jinja_environment(), "report.css")[0]


def render_html(results: Mapping, out_dir: str | Path, *, base_dir: str | Path | None = None,
                trusted: bool = False) -> Path:
    """Write ``out_dir/index.html`` for ``results`` (schema: module docstring).

    Figure paths are resolved against ``base_dir`` (default ``out_dir``) and must stay inside
    it unless ``trusted`` (InputError, nothing written). Each section
    is built on its own: a missing section renders as "not run", a malformed one as
    "could not be rendered" with the reason, and neither stops the others.
    """
    out_dir = Path(out_dir)
    figures = _figures(results.get("figures") or {}, Path(base_dir or out_dir), trusted)
    out_dir.mkdir(parents=True, exist_ok=True)
    context: dict = {"errors": {}, "figures": figures}
    for key, build in _SECTIONS.items():
        value = results.get(key)
        context[key] = None
        if value in (None, {}, [], ""):
            continue
        try:
            context[key] = build(value)
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            context["errors"][key] = f"{type(exc).__name__}: {exc}"
    context["meta_raw"] = results.get("meta") or {}
    context["bench_href"] = BENCH_PAGE if (out_dir / BENCH_PAGE).is_file() else None
    html = jinja_environment().get_template("report.html.j2").render(**context)
    return replace_atomically(out_dir / REPORT_FILES["html"], html.encode("utf-8"))


def render_pdf(html_path: str | Path, pdf_path: str | Path) -> Path:
    """Print the HTML report to PDF with WeasyPrint (print stylesheet of the template).

    WeasyPrint's DeprecationWarning about a missing libharfbuzz-subset0 is silenced
    (fonts are then embedded whole); missing system fonts only degrade the glyphs.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="HarfBuzz-Subset", category=DeprecationWarning)
        try:
            import weasyprint
        except (ImportError, OSError) as exc:   # OSError: pango/cairo libraries missing
            raise SosdynError(f"PDF export needs WeasyPrint and pango ({exc}). "
                              "Try: pip install 'sosdyn[report]'") from exc
    pdf_path = Path(pdf_path)
    pdf_path.parent.mkdir(parents=True, exist_ok=True)
    return replace_atomically(pdf_path, weasyprint.HTML(filename=str(html_path)).write_pdf())


def build_report(results_json_path: str | Path, out_dir: str | Path, *,
                 trusted: bool = False) -> dict[str, Path]:
    """``results.json`` -> ``out_dir/index.html`` and ``out_dir/report.pdf``.

    Figure paths in the results are relative to the folder of ``results.json`` and must stay
    inside it unless ``trusted`` (the experiments' own results).
    Returns ``{"html": path, "pdf": path}``.
    """
    results_json_path = Path(results_json_path)
    results = load_results(results_json_path)
    html = render_html(results, out_dir, base_dir=results_json_path.parent, trusted=trusted)
    return {"html": html, "pdf": render_pdf(html, Path(out_dir) / REPORT_FILES["pdf"])}

"""The benchmark report: ``reports/bench/index.html``, apart from the user report.

The user report (:mod:`sosdyn.report.html`) holds what a user of a fitted model needs:
findings, figures, accuracy, robustness, certificates and fit timings. Solver tables,
profiles, scaling sweeps and the one-state prediction timings go on this page instead, built
from what the benchmarks wrote into one folder:

* ``summary.md`` (``make bench``) and ``sos.md`` (``make bench-sos``), then every other
  ``*.md`` of the folder (by name) that is not already copied into those two (the n-scaling
  tables are), rendered as they are; their images (``scaling_K.png``, ...)
  are linked relative to the folder, and links between these files become links within the page;
* ``predict.json`` (``python -m problems.bench.predict``): one table row per model, the
  median seconds of ``model.predict`` on one row and of ``model.predictor()``, the speed-up
  and the largest relative difference;
* every other ``*.json`` of the folder, linked as raw data.

A missing input is listed as "not run"; nothing else is read.
"""
from __future__ import annotations

import json
from pathlib import Path

from ..files import replace_atomically
from .html import jinja_environment, markdown_html

BENCH_PAGES = (("summary.md", "Learner benchmarks", "make bench"),
               ("sos.md", "SOS layer benchmarks", "make bench-sos"))
PREDICT_FILE = "predict.json"
PREDICT_COLUMNS = ("model", "model.predict, one row", "model.predictor()", "speed-up", "Python export, one row",
                   "max. relative difference", "predictor within target")


def _micro(seconds) -> str:
    return "—" if seconds is None else f"{seconds * 1e6:.1f} µs"


def predict_rows(data: dict) -> list[list[str]]:
    """The cells of the one-state prediction table from a ``predict.json``."""
    return [[f"{r['shape']}, K = {r['K']}, n = {r['n']}, field degree {r['field_degree']}"
             + (f", warp of {r['warp_bumps']} bumps" if r.get("warp_bumps") else ""),
             _micro(r.get("predict_s")), _micro(r.get("predictor_s")),
             "—" if r.get("speedup") is None else f"{r['speedup']:.1f}×",
             _micro(r.get("python_export_s")),
             "—" if r.get("max_rel_diff") is None else f"{r['max_rel_diff']:.1e}",
             "yes" if r.get("within_target") else "no"] for r in data.get("rows", [])]


def predict_headers(data: dict | None) -> tuple:
    """The table's headings; the last names the target the file was measured against (its ``target_s``)."""
    if not data or data.get("target_s") is None:
        return PREDICT_COLUMNS
    return PREDICT_COLUMNS[:-1] + (f"predictor ≤ {data['target_s'] * 1e6:g} µs",)


def render_bench(bench_dir: str | Path) -> Path:
    """Write ``bench_dir/index.html`` from the benchmark outputs in ``bench_dir``."""
    bench_dir = Path(bench_dir)
    known = {name for name, _, _ in BENCH_PAGES}
    main_text = "".join((bench_dir / name).read_text(encoding="utf-8") for name in known
                        if (bench_dir / name).is_file())
    extra = [(p.name, p.stem, None) for p in sorted(bench_dir.glob("*.md"))
             if p.name not in known and p.read_text(encoding="utf-8").strip() not in main_text]
    pages = [*BENCH_PAGES, *extra]
    sections = []
    for name, title, command in pages:
        path = bench_dir / name
        text = path.read_text(encoding="utf-8") if path.is_file() else None
        if text is not None:
            for other, _, _ in pages:
                text = text.replace(f"]({other})", f"](#{Path(other).stem})")
        sections.append({"id": Path(name).stem, "title": title, "command": command,
                         "html": None if text is None else markdown_html(text)})
    predict = bench_dir / PREDICT_FILE
    data = json.loads(predict.read_text(encoding="utf-8")) if predict.is_file() else None
    rows = None if data is None else predict_rows(data)
    raw = sorted(p.name for p in bench_dir.glob("*.json"))
    html = jinja_environment().get_template("bench.html.j2").render(
        sections=sections, predict={"headers": predict_headers(data), "rows": rows}, raw=raw)
    return replace_atomically(bench_dir / "index.html", html.encode("utf-8"))

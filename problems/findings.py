"""The findings of the user report, written from the results sections alone (``accuracy``,
``certificates``, ``diagnostics``: :func:`problems.results.results_sections`), so a fresh run and a
``results.json`` rendered again later give the same words, and no sentence can drift from the
numbers beside it.

Each finding is ``{"title", "text", "numbers"}``. ``numbers`` holds every value the text quotes:
labels ``"<shape>: <quantity>"`` (a table, one row per shape) and plain labels; the text quotes
only these values, their column's smallest, largest and mean, and counts.
``text`` uses the report's small markup subset (``<b>``, ``<i>``, ``<br>``, character entities;
:func:`sosdyn.report.html.markup`).
"""
from __future__ import annotations

import re

import numpy as np
from markupsafe import escape

from sosdyn.report.html import fmt

DEFAULT, PAPER_METHOD, ICA, CUBIC, SEDS, GMR = "CDSP", "CDSP (paper)", "CDSP-ICA", "CDSP-cubic", "SEDS-like", "GMR"
#: The certified variants with the paper's settings (no pre-warp, the paper's K), beside the default.
PAPER_CERTIFIED = (PAPER_METHOD, ICA, CUBIC, SEDS)
#: Two methods' mean DTWD on a shape count as the same within this relative difference.
SAME_RTOL = 1e-3


def _ok(sections, shape, method) -> dict | None:
    """The accuracy entry of a fit that ran (has a DTWD), else None."""
    e = (sections.get("accuracy") or {}).get(shape, {}).get(method)
    return e if e and (e.get("dtwd_total") or {}).get("mean") is not None else None


def _dtwd(e) -> float:
    return e["dtwd_total"]["mean"]


def _collapse(sections, shape, method) -> dict | None:
    return ((sections.get("certificates") or {}).get(shape, {}).get(method) or {}).get("metric_collapse")


def _diag(sections, shape, method) -> dict:
    return (sections.get("diagnostics") or {}).get(shape, {}).get(method) or {}


def num(x, digits=3) -> str:
    """A measured value in a sentence: ``digits`` significant digits (:func:`fmt`)."""
    return fmt(float(x), digits)


def span(values, digits=3) -> str:
    """"a–b" from the smallest to the largest value, or "a" when they print the same (counts as
    integers, other values to ``digits`` significant digits)."""
    def text(v):
        return str(int(v)) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else num(v, digits)
    lo, hi = text(min(values)), text(max(values))
    return lo if lo == hi else f"{lo}–{hi}"


def _shapes(sections) -> list[str]:
    return list(sections.get("accuracy") or {})


def largest_difference(sections, a, b) -> float | None:
    """Largest relative difference |DTWD_a − DTWD_b| / DTWD_b of two methods' mean DTWD over
    the shapes both ran on; None if there are none."""
    pairs = [(_ok(sections, s, a), _ok(sections, s, b)) for s in _shapes(sections)]
    diffs = [abs(_dtwd(x) - _dtwd(y)) / abs(_dtwd(y)) for x, y in pairs if x and y]
    return max(diffs) if diffs else None


def coincide(sections, a, b, rtol=SAME_RTOL) -> bool:
    """Do methods a and b give the same mean DTWD (within ``rtol``) on every shape both ran on?"""
    diff = largest_difference(sections, a, b)
    return diff is not None and diff <= rtol


def _rel_decrease(hist) -> float:
    """Relative decrease of the cost from the first to the last row of a history."""
    c0, c1 = hist[0]["cost"], hist[-1]["cost"]
    return (c0 - c1) / c0 if c0 else 0.0


def _paper_collapse(sections) -> dict | None:
    """(1) collapse of the paper's polynomial metric for linear sub-systems."""
    rows = []
    for s in _shapes(sections):
        p, i, col = _ok(sections, s, PAPER_METHOD), _ok(sections, s, ICA), _collapse(sections, s, PAPER_METHOD)
        dp, di = _diag(sections, s, PAPER_METHOD), _diag(sections, s, ICA)
        if p and i and col and dp.get("final_cost") and di.get("final_cost"):
            rows.append((s, col, dp["final_cost"] / di["final_cost"], _dtwd(p) / _dtwd(i)))
    if not rows:
        return None
    numbers = {}
    for s, col, cost, dratio in rows:
        numbers[f"{s}: max eig. with M(0)"] = col["max eig. with M(0)"]
        numbers[f"{s}: cost paper / ICA"] = cost
        numbers[f"{s}: DTWD paper / ICA"] = dratio
    eigs = [col["max eig. with M(0)"] for _, col, _, _ in rows]
    n_collapse = sum(bool(col["M(0) certifies"]) for _, col, _, _ in rows)
    verb = "adds nothing" if n_collapse == len(rows) else f"is needed on {len(rows) - n_collapse} shapes"
    text = (f"With linear sub-systems the degree-2 metric of the paper {verb}: on "
            f"<b>{n_collapse} of {len(rows)}</b> shapes the constant part M(0) alone certifies the "
            f"fields that <i>CDSP (paper)</i> learned (largest generalised eigenvalue of the "
            f"contraction matrix with M(0): {span(eigs)}, ≤ 0 means certified), as dM(z)[A z] "
            f"vanishing at z = 0 predicts. Its least-squares cost is "
            f"<b>{span([c for _, _, c, _ in rows])}×</b> that of <i>CDSP-ICA</i> (constant metric, "
            f"ICA solver) and its DTWD {span([d for *_, d in rows])}×.")
    diff = largest_difference(sections, PAPER_METHOD, SEDS)
    if diff is not None:
        numbers["largest DTWD difference to SEDS-like (%)"] = 100 * diff
        numbers["counted as the same within (%)"] = 100 * SAME_RTOL
        if diff <= SAME_RTOL:
            text += (f" Its reproductions are those of <i>SEDS-like</i> (M = I) on every shape: the mean "
                     f"DTWDs differ by at most {num(100 * diff)} % (the same within "
                     f"{100 * SAME_RTOL:g} %), as if the alternation had stayed at the identity "
                     f"metric it starts from.")
        else:
            text += (f" Its mean DTWD differs from <i>SEDS-like</i>'s (M = I) by up to {num(100 * diff)} % "
                     f"(more than the {100 * SAME_RTOL:g} % counted as the same).")
    return {"title": "The paper's polynomial metric and a constant one, for linear sub-systems",
            "text": text, "numbers": numbers}


def _alternation(sections) -> dict | None:
    """(2) plain alternation stalls, ICA does not."""
    rows = []
    for s in _shapes(sections):
        hp, hi = _diag(sections, s, PAPER_METHOD).get("history"), _diag(sections, s, ICA).get("history")
        if _ok(sections, s, PAPER_METHOD) and _ok(sections, s, ICA) and hp and hi:
            margins = [r["margin"] for r in hp if r.get("step") == "metric" and "margin" in r]
            rows.append((s, hp, hi, min(margins) if margins else None))
    if not rows:
        return None
    numbers = {}
    for s, hp, hi, margin in rows:
        numbers[f"{s}: alternation solves"] = len(hp)
        numbers[f"{s}: alternation cost decrease (%)"] = 100 * _rel_decrease(hp)
        if margin is not None:
            numbers[f"{s}: smallest metric-step margin"] = margin
        numbers[f"{s}: ICA solves"] = len(hi)
        numbers[f"{s}: ICA cost decrease (%)"] = 100 * _rel_decrease(hi)
    alt = [100 * _rel_decrease(hp) for _, hp, _, _ in rows]
    ica = [100 * _rel_decrease(hi) for _, _, hi, _ in rows]
    alt_n, ica_n = [len(hp) for _, hp, _, _ in rows], [len(hi) for _, _, hi, _ in rows]
    margins = [m for *_, m in rows if m is not None]
    stalls = max(alt) < min(ica)
    text = (f"Plain alternation of the dynamics and metric steps stops after {span(alt_n)} convex "
            f"solves having lowered the cost by <b>{span(alt)} %</b>")
    if margins:
        text += (f"; each metric step finds a contraction margin of only {span(margins)} (the fields "
                 "sit on the boundary of the feasible set, so the next dynamics step cannot move)")
    text += (f". The inner convex approximation (ICA) updates fields and metric jointly and lowers the "
             f"same cost by <b>{span(ica)} %</b> in {span(ica_n)} solves.")
    title = ("Plain alternation stalls; ICA does not" if stalls else
             "Cost decrease of plain alternation and of ICA")
    return {"title": title, "text": text, "numbers": numbers}


def _cubic(sections) -> dict | None:
    """(3) cubic fields: the state-dependent metric is needed; what it buys in DTWD."""
    rows = []
    for s in _shapes(sections):
        c, i, col = _ok(sections, s, CUBIC), _ok(sections, s, ICA), _collapse(sections, s, CUBIC)
        if c and i and col:
            rows.append((s, col, 100 * (1.0 - _dtwd(c) / _dtwd(i)), bool(c.get("certified"))))
    if not rows:
        return None
    numbers = {}
    for s, col, gain, _ in rows:
        numbers[f"{s}: max eig. with M(0)"] = col["max eig. with M(0)"]
        numbers[f"{s}: DTWD change cubic vs ICA (%)"] = gain
    needed = sum(not col["M(0) certifies"] for _, col, _, _ in rows)
    full = sum(cert for *_, cert in rows)
    gains = [g for _, _, g, _ in rows]
    eigs = [col["max eig. with M(0)"] for _, col, _, _ in rows]
    text = (f"With cubic sub-systems, on <b>{needed} of {len(rows)}</b> shapes M(0) alone does not "
            f"certify the learned fields (largest generalised eigenvalue with M(0) up to {num(max(eigs))}; "
            f"&gt; 0 means not certified), while the full M(z) certifies them on {full} of {len(rows)}. "
            f"In accuracy, <i>CDSP-cubic</i> lowers the DTWD relative to <i>CDSP-ICA</i> on "
            f"{sum(g > 0 for g in gains)} of {len(rows)} shapes; the change ranges from "
            f"<b>{num(min(gains))} %</b> to <b>{num(max(gains))} %</b> (positive = lower DTWD), mean "
            f"{num(float(np.mean(gains)))} %.")
    return {"title": "Cubic fields and the state-dependent metric; what they change in DTWD",
            "text": text, "numbers": numbers}


def default_against_gmr(sections) -> list[dict]:
    """Per shape where both ran: the default CDSP()'s DTWD over GMR's, whether it is certified,
    both grid convergences, and the best certified paper-setting variant with its DTWD over GMR's."""
    rows = []
    for s in _shapes(sections):
        d, g = _ok(sections, s, DEFAULT), _ok(sections, s, GMR)
        if not (d and g):
            continue
        paper = [(m, e) for m in PAPER_CERTIFIED if (e := _ok(sections, s, m)) and e.get("certified")]
        best = min(paper, key=lambda me: _dtwd(me[1])) if paper else None
        rows.append({"shape": s, "ratio": _dtwd(d) / _dtwd(g), "certified": bool(d.get("certified")),
                     "grid": d.get("grid_convergence"), "gmr_grid": g.get("grid_convergence"),
                     "best": best and best[0], "best_ratio": best and _dtwd(best[1]) / _dtwd(g)})
    return rows


def _grids(rows) -> tuple[list[float], list[float]]:
    """Grid convergence (%) of the default and of GMR, where both were measured."""
    pairs = [(r["grid"], r["gmr_grid"]) for r in rows if r["grid"] is not None and r["gmr_grid"] is not None]
    return [100 * a for a, _ in pairs], [100 * b for _, b in pairs]


def _versus_gmr(sections) -> dict | None:
    """(4) the default CDSP() and the paper-setting certified models against GMR."""
    rows = default_against_gmr(sections)
    if not rows:
        return None
    numbers = {}
    for r in rows:
        numbers[f"{r['shape']}: CDSP() DTWD / GMR's"] = r["ratio"]
        if r["best"]:
            numbers[f"{r['shape']}: best paper-setting certified"] = r["best"]
            numbers[f"{r['shape']}: its DTWD / GMR's"] = r["best_ratio"]
        if r["grid"] is not None and r["gmr_grid"] is not None:
            numbers[f"{r['shape']}: grid conv. CDSP() (%)"] = 100 * r["grid"]
            numbers[f"{r['shape']}: grid conv. GMR (%)"] = 100 * r["gmr_grid"]
    ratios = [r["ratio"] for r in rows]
    lower = sum(x < 1 for x in ratios)
    text = (f"The default <i>CDSP()</i>, certified on {sum(r['certified'] for r in rows)} of {len(rows)} "
            f"shapes, reproduces the demonstrations with a DTWD <b>{span(ratios)}×</b> that of "
            f"unconstrained GMR with a mixture of the same size per shape (lower on {lower} of "
            f"{len(rows)} shapes, mean {num(float(np.mean(ratios)))}×).")
    grid, gmr_grid = _grids(rows)
    if grid:
        text += f" It reaches the goal from {span(grid)} % of the grid starts, GMR from {span(gmr_grid)} %."
    best = [r["best_ratio"] for r in rows if r["best"]]
    if best:
        text += (f" With the paper's settings (no pre-warp) the guarantee costs accuracy: the best "
                 f"certified variant per shape has <b>{span(best)}×</b> GMR's DTWD.")
    return {"title": "The certified default against unconstrained GMR", "text": text, "numbers": numbers}


_NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.(\d+))?(?:e([-+]?\d+))?")
SMALL_COUNT = 30      # integers up to this are counts, degrees, seeds ("4 of 4", "M(0)"), not checked


def unquoted(text: str, numbers: dict) -> list[str]:
    """The numbers printed in ``text`` that are none of ``numbers``' values, nor the smallest,
    largest or mean of a column (labels ``"<row>: <column>"``), to the digits printed; integers
    up to :data:`SMALL_COUNT` are counts and pass. Empty for a sentence true to its numbers."""
    columns: dict[str, list[float]] = {}
    for label, value in numbers.items():
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            columns.setdefault(str(label).partition(": ")[2] or str(label), []).append(float(value))
    allowed = [v for col in columns.values() for v in (*col, min(col), max(col), float(np.mean(col)))]
    bad = []
    for match in _NUMBER.finditer(text):
        x, decimals, exponent = float(match.group(0)), match.group(1) or "", match.group(2)
        if x == int(x) and abs(x) <= SMALL_COUNT and not decimals and exponent is None:
            continue
        tol = 0.5 * 10.0 ** (-len(decimals) + int(exponent or 0)) + 1e-12 * abs(x)
        if not any(abs(x - v) <= tol for v in allowed):
            bad.append(match.group(0))
    return bad


def checked(finding: dict) -> dict:
    """``finding`` if its text quotes only its numbers (:func:`unquoted`), else ValueError: a
    sentence of this module is out of step with its data."""
    bad = unquoted(finding["text"], finding["numbers"])
    if bad:
        raise ValueError(f"finding {finding['title']!r} quotes {', '.join(bad)}, not among its numbers")
    return finding


def findings(sections: dict) -> list[dict]:
    """The four findings of the paper comparison, then the failed fits; from ``sections``
    (the results sections, or a whole results dict) only."""
    out = [checked(f) for f in (_paper_collapse(sections), _alternation(sections), _cubic(sections),
                                _versus_gmr(sections)) if f]
    fails = failures(sections)
    if fails:
        out.append({"title": f"Failed fits ({len(fails)})",
                    "text": "<br>".join(f"<b>{_esc(s)} / {_esc(m)}</b>: {_esc(err)}" for s, m, err in fails),
                    "numbers": {}})
    return out


def _esc(text) -> str:
    return str(escape(text))


def failures(sections: dict) -> list[tuple[str, str, str]]:
    """(shape, method, error text) of every failed fit."""
    return [(s, m, d["error"]) for s, per in (sections.get("diagnostics") or {}).items()
            for m, d in per.items() if "error" in d]


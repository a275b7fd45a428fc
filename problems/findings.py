"""The findings of the report: every number computed from the cached entries only.

Each finding is ``{"title", "text", "numbers"}``; ``text`` uses the report's small markup
subset (``<b>``, ``<i>``, ``<br>``, character entities; :func:`sosdyn.report.html.markup`).
"""
from __future__ import annotations

import math

import numpy as np
from markupsafe import escape

from sosdyn.report.html import fmt


PAPER_METHOD, ICA, CUBIC, SEDS, GMR = "CDSP (paper)", "CDSP-ICA", "CDSP-cubic", "SEDS-like", "GMR"
CERTIFIED = (PAPER_METHOD, ICA, CUBIC, SEDS)


def _ok(entries, shape, method):
    e = entries.get(shape, {}).get(method)
    return e if e and e.get("status") == "ok" else None


def _dtwd(e):
    return e["accuracy"]["dtwd_total"]["mean"]


def _f(x, digits=3):
    return fmt(float(x), digits)


def coincide(entries, a, b, rtol=1e-6) -> bool:
    """Do methods a and b give the same mean DTWD (to rtol) on every shape both ran on?"""
    pairs = [(_ok(entries, s, a), _ok(entries, s, b)) for s in entries]
    pairs = [(x, y) for x, y in pairs if x and y]
    return bool(pairs) and all(math.isclose(_dtwd(x), _dtwd(y), rel_tol=rtol) for x, y in pairs)


def _rel_change(hist):
    """(first cost, last cost, relative decrease) of a history."""
    c0, c1 = hist[0]["cost"], hist[-1]["cost"]
    return c0, c1, (c0 - c1) / c0 if c0 else 0.0


def _collapse(entries, shapes) -> dict | None:
    """(1) collapse of the paper's polynomial metric for linear sub-systems."""
    rows = [(s, _ok(entries, s, PAPER_METHOD), _ok(entries, s, ICA)) for s in shapes]
    rows = [(s, p, i) for s, p, i in rows if p and i and p["diagnostics"].get("metric_collapse")]
    if rows:
        numbers, eigs, ratios, dratios = {}, [], [], []
        for s, p, i in rows:
            col = p["diagnostics"]["metric_collapse"]
            eig = col["max_eig_with_constant_metric"]
            eigs.append(eig)
            cost_ratio = p["diagnostics"]["final_cost"] / i["diagnostics"]["final_cost"]
            ratios.append(cost_ratio)
            dratios.append(_dtwd(p) / _dtwd(i))
            numbers[f"{s}: max eig. with M(0)"] = eig
            numbers[f"{s}: cost paper / ICA"] = cost_ratio
        n_collapse = sum(p["diagnostics"]["metric_collapse"]["constant_metric_certifies"] for _, p, _ in rows)
        same = coincide(entries, PAPER_METHOD, SEDS)
        text = (f"With linear sub-systems the degree-2 metric of the paper adds nothing: on "
                f"<b>{n_collapse} of {len(rows)}</b> shapes the constant part M(0) alone certifies the "
                f"fields that <i>CDSP (paper)</i> learned (largest generalised eigenvalue of the "
                f"contraction matrix with M(0): {_f(min(eigs))} to {_f(max(eigs))}, ≤ 0 means "
                f"certified), as it must: dM(z)[A z] vanishes at z = 0. Its least-squares cost is "
                f"<b>{_f(min(ratios))}–{_f(max(ratios))}×</b> that of <i>CDSP-ICA</i> (constant metric, "
                f"ICA solver) and its DTWD {_f(min(dratios))}–{_f(max(dratios))}×.")
        if same:
            text += (" Its reproductions are identical to <i>SEDS-like</i> (M = I) on every shape: "
                     "the fit never left the identity metric it starts from.")
        numbers["DTWD identical to SEDS-like"] = same
        return {"title": "The paper's polynomial metric collapses to a constant one for "
                         "linear sub-systems", "text": text, "numbers": numbers}
    return None


def _alternation(entries, shapes) -> dict | None:
    """(2) plain alternation stalls, ICA does not."""
    rows = [(s, _ok(entries, s, PAPER_METHOD), _ok(entries, s, ICA)) for s in shapes]
    rows = [(s, p, i) for s, p, i in rows if p and i and p["diagnostics"].get("history")
            and i["diagnostics"].get("history")]
    if rows:
        numbers, alt_dec, ica_dec, alt_steps, ica_steps, margins = {}, [], [], [], [], []
        for s, p, i in rows:
            hp, hi = p["diagnostics"]["history"], i["diagnostics"]["history"]
            _, _, dp = _rel_change(hp)
            _, _, di = _rel_change(hi)
            alt_dec.append(dp)
            ica_dec.append(di)
            alt_steps.append(len(hp))
            ica_steps.append(len(hi))
            margins += [r["margin"] for r in hp if r.get("step") == "metric" and "margin" in r]
            numbers[f"{s}: alternation steps / cost decrease"] = f"{len(hp)} / {100 * dp:.3g} %"
            numbers[f"{s}: ICA steps / cost decrease"] = f"{len(hi)} / {100 * di:.3g} %"
        text = (f"Plain alternation of the dynamics and metric steps stops after "
                f"{min(alt_steps)}–{max(alt_steps)} convex solves having lowered the cost by "
                f"<b>{_f(100 * min(alt_dec))}–{_f(100 * max(alt_dec))} %</b>")
        if margins:
            text += (f"; each metric step finds a contraction margin of only {_f(min(margins))}–"
                     f"{_f(max(margins))} (the fields sit on the boundary of the feasible set, so the "
                     "next dynamics step cannot move)")
        text += (f". The inner convex approximation (ICA) updates fields and metric jointly and "
                 f"lowers the same cost by <b>{_f(100 * min(ica_dec))}–{_f(100 * max(ica_dec))} %</b> in "
                 f"{min(ica_steps)}–{max(ica_steps)} solves.")
        return {"title": "Plain alternation stalls; ICA does not", "text": text, "numbers": numbers}
    return None


def _cubic(entries, shapes) -> dict | None:
    """(3) cubic fields: the state-dependent metric is needed; what it buys in DTWD."""
    rows = [(s, _ok(entries, s, CUBIC), _ok(entries, s, ICA)) for s in shapes]
    rows = [(s, c, i) for s, c, i in rows if c and i and c["diagnostics"].get("metric_collapse")]
    if rows:
        numbers, needed, gains = {}, 0, []
        for s, c, i in rows:
            col = c["diagnostics"]["metric_collapse"]
            needed += not col["constant_metric_certifies"]
            gain = 1.0 - _dtwd(c) / _dtwd(i)
            gains.append(gain)
            numbers[f"{s}: max eig. with M(0)"] = col["max_eig_with_constant_metric"]
            numbers[f"{s}: DTWD cubic / ICA"] = _dtwd(c) / _dtwd(i)
        better = sum(g > 0 for g in gains)
        text = (f"With cubic sub-systems the state-dependent metric is necessary: on <b>{needed} of "
                f"{len(rows)}</b> shapes M(0) alone does not certify the learned fields (largest "
                f"generalised eigenvalue with M(0) up to {_f(max(numbers[f'{s}: max eig. with M(0)'] for s, _, _ in rows))} "
                f"&gt; 0) while the full M(z) does. In accuracy, <i>CDSP-cubic</i> lowers the DTWD "
                f"relative to <i>CDSP-ICA</i> on {better} of {len(rows)} shapes; the change ranges "
                f"from <b>{_f(100 * min(gains))} %</b> to <b>{_f(100 * max(gains))} %</b> "
                f"(positive = better), mean {_f(100 * float(np.mean(gains)))} %.")
        return {"title": "Cubic fields need the state-dependent metric; what they change in DTWD",
                "text": text, "numbers": numbers}
    return None


def _versus_gmr(entries, shapes) -> dict | None:
    """(4) certified models vs GMR."""
    rows = []
    for s in shapes:
        g = _ok(entries, s, GMR)
        certs = [(m, _ok(entries, s, m)) for m in CERTIFIED]
        certs = [(m, e) for m, e in certs if e and e["accuracy"].get("certified")]
        if g and certs:
            best_m, best = min(certs, key=lambda me: _dtwd(me[1]))
            rows.append((s, best_m, _dtwd(best) / _dtwd(g), g["accuracy"].get("grid_convergence"),
                         best["accuracy"].get("grid_convergence")))
    if rows:
        numbers = {}
        for s, m, r, _, _ in rows:      # one row per shape in the report's table
            numbers[f"{s}: best certified method"] = m
            numbers[f"{s}: its DTWD / GMR's"] = r
        numbers.update({f"{s}: grid convergence GMR": gg for s, _, _, gg, _ in rows if gg is not None})
        ratios = [r for _, _, r, _, _ in rows]
        ggs = [gg for *_, gg, _ in rows if gg is not None]
        cgs = [cg for *_, cg in rows if cg is not None]
        text = (f"The guarantee costs accuracy: the best certified model's DTWD is "
                f"<b>{_f(min(ratios))}–{_f(max(ratios))}×</b> that of unconstrained GMR with the same "
                f"mixture (mean {_f(float(np.mean(ratios)))}×).")
        if ggs and cgs:
            text += (f" In exchange, the certified models reach the goal from {_f(100 * min(cgs))}–"
                     f"{_f(100 * max(cgs))} % of the grid starts, GMR from {_f(100 * min(ggs))}–"
                     f"{_f(100 * max(ggs))} %.")
        return {"title": "Certified models vs GMR: the accuracy gap", "text": text, "numbers": numbers}
    return None


def findings(entries: dict) -> list[dict]:
    """The four findings (module docstring of problems.run), then the failed fits; numbers from
    the entries only."""
    shapes = list(entries)
    out = [f for f in (_collapse(entries, shapes), _alternation(entries, shapes), _cubic(entries, shapes),
                       _versus_gmr(entries, shapes)) if f]
    fails = failures(entries)
    if fails:
        out.append({"title": f"Failed fits ({len(fails)})",
                    "text": "<br>".join(f"<b>{s} / {m}</b>: {_esc(err)}" for s, m, err in fails),
                    "numbers": {}})
    return out


def _esc(text):
    return str(escape(text))


def failures(entries: dict) -> list[tuple[str, str, str]]:
    """(shape, method, error text) of every failed fit."""
    return [(s, m, e.get("error") or "") for s, per in entries.items() for m, e in per.items()
            if e.get("status") != "ok"]

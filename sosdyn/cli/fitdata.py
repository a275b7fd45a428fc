"""What ``sosdyn fit`` does around the fit: shipped data sets, preprocessing, crossings, and the
table of how the fitted model reproduces each demonstration.

``dataset:NAME`` reads :func:`sosdyn.load_dataset` (a pose set with its orientations: a pose model; the loader's notes, e.g.
hammer's declared time step, are printed). ``--smooth``, ``--trim-rest`` and ``--align-ends``
are the options of the family's ``prepare`` (:func:`sosdyn.preprocess`'s), which also warns about
crossing demonstrations when the family cannot follow them (:mod:`sosdyn.lfd.data.crossing`); after
the fit the model's ``score`` is printed (with the time each reproduction takes to reach the goal), a
caution under the certificate when some do not arrive within twice their demonstration's duration
(:func:`~sosdyn.lfd.rollout.quality.arrival_caution`), and a warning when a reproduction deviates by more
than :data:`DEVIATION_WARN` of the data's extent (bounding-box diagonal).
"""
from __future__ import annotations

import warnings

import numpy as np
import typer
from rich.markup import escape

from ..lfd.data.datasets import load_dataset
from ..lfd.rollout.quality import arrival_caution
from .base import State, info, out
from .paths import DATASET_PREFIX

DEVIATION_WARN = 0.10


def parse_smooth(value: str) -> str | int:
    """``--smooth``: auto, off, or an odd window >= 5 (samples)."""
    if value in ("auto", "off"):
        return value
    try:
        window = int(value)
    except ValueError:
        raise typer.BadParameter(f"must be auto, off or an odd number of samples >= 5, got {value!r}.") from None
    if window < 5 or window % 2 == 0:
        raise typer.BadParameter(f"the window must be odd and >= 5 samples, got {window}.")
    return window


def parse_align(value: str) -> bool | str | float:
    """``--align-ends``: auto, on, off, or the largest shift accepted (data units; aligns)."""
    if value in ("auto", "on", "off"):
        return {"auto": "auto", "on": True, "off": False}[value]
    try:
        limit = float(value)
    except ValueError:
        raise typer.BadParameter(f"must be auto, on, off or a distance > 0, got {value!r}.") from None
    if not 0 < limit < float("inf"):
        raise typer.BadParameter(f"the largest shift must be a finite number > 0, got {value!r}.")
    return limit


def load_dataset_input(spec: str, dt: float | None):
    """The shipped set ``dataset:NAME`` (a pose set with its orientations: a pose model); the loader's notes printed."""
    name = spec.removeprefix(DATASET_PREFIX)
    with warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        data = load_dataset(name, dt=dt)
    for note in notes:
        info(f"note: {escape(str(note.message))}")
    return data


def prepare(family, data, smooth: str | int, trim_rest: bool, align):
    """``data`` prepared by ``family`` (:meth:`~sosdyn.lfd.model.base.MotionModel.prepare`), what was
    done and its cautions (crossings) printed."""
    max_shift = align if isinstance(align, float) else None
    result, notes, cautions = family.prepare(data, smooth_window=smooth, trim_rest=trim_rest,
                                             align=True if max_shift is not None else align, max_shift=max_shift)
    for line in notes:
        info(escape(line))
    for message in cautions:
        if not State.quiet:
            out.print(f"[yellow]warning:[/] {escape(message)}", soft_wrap=True)
    return result


def print_arrival(rows: list[dict] | None, gamma: float | None) -> None:
    """The caution of :func:`~sosdyn.lfd.rollout.quality.arrival_caution` (printed under the certificate)."""
    message = None if rows is None else arrival_caution(rows, gamma)
    if message:
        out.print(f"[yellow]arrival:[/] {escape(message)}", soft_wrap=True)


def print_score(rows: list[dict] | None, data) -> None:
    """The table of the model's ``score`` rows (None: --quiet, nothing) and a warning for reproductions
    far from their demonstration."""
    if rows is None:
        return
    pos = np.vstack([d.pos for d in data])
    extent = float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0)))
    u = data.units or "units"
    out.print(f"reproduction of each demonstration from its start ({u}; reaches goal = the first time within 1% "
              f"of the extent {extent:.4g}, 'never' = not within twice the demo's duration):", highlight=False,
              soft_wrap=True)
    angles = any("max_dev_deg" in r for r in rows)       # a pose model's rows also score the orientation (deg)
    if angles:
        out.print("orientations: deviation in deg; the goal is reached within 1 deg of the goal orientation too.",
                  highlight=False)
    out.print(f"{'demo':>4}  {'mean dev':>10}  {'max dev':>10}  " + (f"{'mean deg':>8}  {'max deg':>8}  " if angles else "")
              + f"{'reaches goal s':>14}  {'demo s':>7}  at goal", highlight=False)
    for r in rows:
        arrival = f"{r['arrival_s']:.3g}" if np.isfinite(r["arrival_s"]) else "never"
        out.print(f"{r['demo']:>4}  {r['mean_dev']:>10.4g}  {r['max_dev']:>10.4g}  "
                  + (f"{r['mean_dev_deg']:>8.3g}  {r['max_dev_deg']:>8.3g}  " if angles else "")
                  + f"{arrival:>14}  {r['duration_s']:>7.3g}  {'yes' if r['at_goal'] else 'NO'}", highlight=False)
    far = [r for r in rows if r["max_dev"] > DEVIATION_WARN * extent]
    if far:
        worst = max(far, key=lambda r: r["max_dev"])
        out.print(f"[yellow]warning:[/] {len(far)} of {len(rows)} reproductions deviate from their demonstration "
                  f"by more than {DEVIATION_WARN:.0%} of the data's extent (worst: demo {worst['demo']}, "
                  f"{worst['max_dev']:.4g} {escape(u)}). Try: more components (--components), --smooth, or check "
                  "the demonstrations for crossings.", soft_wrap=True)

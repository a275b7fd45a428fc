"""The synthesised hand-drawn winding set ``sosdyn/lfd/data/datasets/winding`` (issue 36).

``python -m problems winding-shapes [--out DIR] [--seed 36] [--figure PNG]`` writes, per shape,
``demo_NN.csv`` (``time_ms,x,y``), a ``manifest.csv`` and (``--figure``) an overview PNG.

Strokes that wind around the goal: inward spirals of 180, 270 and 360 degrees, a hook that swings
out and 270 degrees around the goal before it lands, a "G" whose tail loops back in to the goal, a
snail that swings out and winds a full turn in; and three that start near the goal and swing far
out before winding back (a hook, a loop and a curl: 5-15 times the start's distance). They are synthesised as the crossing set is
(``problems/crossing_shapes.py``, whose steps this module reuses): a perturbed chord-length
spline through the shape's waypoints, the two-thirds power law of drawing speed, and a mouse
logger (jittered integer-ms events, integer pixels, rests at both ends). The waypoints of the
spirals come from polar curves r(theta) about the goal (:func:`polar`); the goal is the origin.
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.report.figures.style import new_figure
from .crossing_shapes import SPEED, log_samples, pen_path, timing

OUT = DATASETS_DIR / "winding"
SEED = 36
DEMOS = 7


def polar(theta0_deg: float, turn_deg: float, radius, n: int = 12) -> list[tuple[float, float]]:
    """n + 1 waypoints (px) equally spaced in arc length along theta = theta0 + turn * s,
    r = radius(s), s in [0, 1], the last the goal (0, 0); a positive turn winds counter-clockwise.
    Equal spacing keeps the waypoints near the goal as far apart as the others, so the per-demo
    jitter of every waypoint (:func:`~problems.crossing_shapes.pen_path`) does not tie knots there."""
    s = np.linspace(0.0, 1.0, 2001)
    th = np.radians(theta0_deg + turn_deg * s)
    r = np.asarray(radius(s), dtype=float)
    xy = np.column_stack([r * np.cos(th), r * np.sin(th)])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
    pts = [tuple(float(v) for v in xy[np.searchsorted(arc, a)]) for a in np.linspace(0, arc[-1], n + 1)[:-1]]
    return pts + [(0.0, 0.0)]


def _inward(r0: float, power: float = 0.8):
    """r(s) = r0 (1 - s)^power: a spiral that only approaches the goal."""
    return lambda s: r0 * (1.0 - s) ** power


def _swing(r0: float, out: float, power: float = 1.0):
    """r(s) = r0 (1 + out sin(pi s^power)) (1 - s): out to about (1 + out) r0 / 2 and back in
    (power < 1: out sooner)."""
    return lambda s: r0 * (1.0 + out * np.sin(np.pi * s ** power)) * (1.0 - s)


#: Shape name -> (description, waypoints (px, y up, the last the goal)).
SHAPES = {
    "spiral180": ("an inward spiral, half a turn counter-clockwise", polar(-90.0, 180.0, _inward(230.0))),
    "spiral270": ("an inward spiral, three quarters of a turn clockwise", polar(120.0, -330.0, _inward(230.0))),
    "spiral360": ("an inward spiral, a full turn counter-clockwise", polar(200.0, 410.0, _inward(230.0), n=16)),
    "hook": ("a hook: out to about twice the start's distance from the goal while winding 270 degrees "
             "counter-clockwise around it, then in", polar(30.0, 300.0, _swing(110.0, 2.5), n=14)),
    "G": ("a G: from the upper terminal counter-clockwise round the bowl, up the right side, then the tail "
          "loops back in along the bar to the goal near the centre",
          [(95, 115), (30, 150), (-50, 140), (-115, 85), (-140, 0), (-115, -85), (-50, -135), (30, -140),
           (100, -100), (130, -30), (110, 20), (60, 25), (20, 10), (0, 0)]),
    "snail": ("a snail: out and a full turn clockwise, the distance to the goal first growing, then shrinking",
              polar(-60.0, -420.0, _swing(120.0, 1.6), n=16)),
    "nearhook": ("a hook that starts near the goal: out to about 6 times the start's distance while winding "
                 "300 degrees counter-clockwise, then in", polar(30.0, 300.0, _swing(40.0, 12.0), n=14)),
    "loop": ("a loop from beside the goal: out to about 15 times the start's distance and round 300 degrees "
             "counter-clockwise back in", polar(30.0, 300.0, _swing(30.0, 20.0, 0.7), n=14)),
    "curl": ("a curl that starts near the goal: out to about 5 times the start's distance and nearly a full turn "
             "clockwise in", polar(-60.0, -340.0, _swing(40.0, 10.0, 0.7), n=16)),
}


def winding_angle(xy: np.ndarray) -> float:
    """The total angle (degrees, signed: counter-clockwise positive) that the curve ``xy`` (T, 2)
    turns about the origin, samples at the origin skipped."""
    p = xy[np.any(xy != 0, axis=1)]
    return float(np.degrees(np.sum(np.diff(np.unwrap(np.arctan2(p[:, 1], p[:, 0]))))))


def generate(seed: int = SEED) -> dict:
    """{shape: [(time_ms, xy) per demo]}."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, (_, waypoints) in SHAPES.items():
        demos = []
        for _ in range(DEMOS):
            path = pen_path(waypoints, rng)
            demos.append(log_samples(path, timing(path, SPEED * np.exp(rng.normal(scale=0.15))), rng))
        out[name] = demos
    return out


def write(data: dict, out_dir: Path) -> None:
    """The CSVs and one manifest for all shapes (file, samples, duration, start, end, winding angle)."""
    rows = []
    for name, demos in data.items():
        folder = Path(out_dir) / name
        folder.mkdir(parents=True, exist_ok=True)
        for k, (ms, xy) in enumerate(demos):
            file = f"demo_{k:02d}.csv"
            with open(folder / file, "w", newline="") as handle:
                w = csv.writer(handle)
                w.writerow(["time_ms", "x", "y"])
                w.writerows(np.column_stack([ms, xy]).tolist())
            rows.append([f"{name}/{file}", len(ms), int(ms[-1]), *xy[0], *xy[-1], round(winding_angle(xy))])
    with open(Path(out_dir) / "manifest.csv", "w", newline="") as handle:
        w = csv.writer(handle)
        w.writerow(["file", "samples", "duration_ms", "start_x", "start_y", "end_x", "end_y", "winding_deg"])
        w.writerows(rows)


def overview(data: dict, png: Path) -> Path:
    """All shapes, one panel each, demos as logged (px)."""
    fig = new_figure(15, 8)
    for i, (name, demos) in enumerate(data.items()):
        ax = fig.add_subplot(2, (len(data) + 1) // 2, i + 1)
        for _, xy in demos:
            ax.plot(xy[:, 0], xy[:, 1], lw=0.8, color="#0072B2")
            ax.plot(*xy[0], "o", ms=3, color="0.3")
        ax.plot(0, 0, "*", ms=10, color="black")
        ax.set_title(name)
        ax.set_aspect("equal")
    fig.savefig(png, dpi=72)
    return png


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m problems winding-shapes", description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, default=OUT, help="output folder (default: the shipped set)")
    p.add_argument("--seed", type=int, default=SEED)
    p.add_argument("--figure", type=Path, default=None, help="also write an overview PNG here")
    args = p.parse_args(list(argv or []))
    data = generate(args.seed)
    write(data, args.out)
    if args.figure:
        overview(data, args.figure)
    print(f"winding-shapes: {len(data)} shapes, {sum(map(len, data.values()))} demos -> {args.out}")
    return 0

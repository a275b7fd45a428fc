"""The synthesised hand-drawn winding set ``sosdyn/lfd/data/datasets/winding`` (issue 36).

``python -m problems winding-shapes [--out DIR] [--seed 36] [--figure PNG]`` writes, per shape,
``demo_NN.csv`` (``time_ms,x,y``), a ``manifest.csv`` and (``--figure``) an overview PNG.

Strokes that wind around the goal: inward spirals of 180, 270 and 360 degrees, a hook that swings
out and 270 degrees around the goal before it lands, a "G" whose tail loops back in to the goal, a
snail that swings out and winds a full turn in; and three that start near the goal and swing far
out before winding back (a hook, a loop and a curl: 6-20 times the start's distance). They are
synthesised as the crossing set is (``problems/crossing_shapes.py``, whose generator, figure and
command line this module reuses): a perturbed chord-length
spline through the shape's waypoints, the two-thirds power law of drawing speed, and a mouse
logger (jittered integer-ms events, integer pixels, rests at both ends). The waypoints of the
spirals come from polar curves r(theta) about the goal (:func:`polar`); the goal is the origin.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sosdyn.lfd.data.datasets import DATASETS_DIR
from .crossing_shapes import LOG_COLUMNS, generator_main, log_row, write_set

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
PATHS = {
    "spiral180": ("an inward spiral, half a turn counter-clockwise", polar(-90.0, 180.0, _inward(230.0))),
    "spiral270": ("an inward spiral of 270-300 degrees clockwise", polar(120.0, -330.0, _inward(230.0))),
    "spiral360": ("an inward spiral, a full turn counter-clockwise", polar(200.0, 410.0, _inward(230.0), n=16)),
    "hook": ("a hook: out to about twice the start's distance from the goal while winding 270 degrees "
             "counter-clockwise around it, then in", polar(30.0, 300.0, _swing(110.0, 2.5), n=14)),
    "G": ("a G: from the upper terminal counter-clockwise round the bowl, up the right side, then the tail "
          "loops back in along the bar to the goal near the centre",
          [(95, 115), (30, 150), (-50, 140), (-115, 85), (-140, 0), (-115, -85), (-50, -135), (30, -140),
           (100, -100), (130, -30), (110, 20), (60, 25), (20, 10), (0, 0)]),
    "snail": ("a snail: out and a full turn clockwise, the distance to the goal first growing, then shrinking",
              polar(-60.0, -420.0, _swing(120.0, 1.6), n=16)),
    "nearhook": ("a hook that starts near the goal: out to about 8 times the start's distance while winding "
                 "300 degrees counter-clockwise, then in", polar(30.0, 300.0, _swing(40.0, 12.0), n=14)),
    "loop": ("a loop from beside the goal: out to about 18 times the start's distance and round 300 degrees "
             "counter-clockwise back in", polar(30.0, 300.0, _swing(30.0, 20.0, 0.7), n=14)),
    "curl": ("a curl that starts near the goal: out to about 8 times the start's distance and nearly a full turn "
             "clockwise in", polar(-60.0, -340.0, _swing(40.0, 10.0, 0.7), n=16)),
}


#: The same as :data:`~problems.crossing_shapes.SHAPES` takes them: (description, [waypoints], demos), one family.
SHAPES = {name: (what, [waypoints], DEMOS) for name, (what, waypoints) in PATHS.items()}


def winding_angle(xy: np.ndarray) -> float:
    """The total angle (degrees, signed: counter-clockwise positive) that the curve ``xy`` (T, 2)
    turns about the origin, samples at the origin skipped."""
    p = xy[np.any(xy != 0, axis=1)]
    return float(np.degrees(np.sum(np.diff(np.unwrap(np.arctan2(p[:, 1], p[:, 0]))))))


def write(data: dict, out_dir: Path) -> None:
    """The CSVs and one manifest for all shapes (file, samples, duration, start, end, winding angle)."""
    write_set(data, out_dir, [*LOG_COLUMNS, "winding_deg"],
              lambda name, k, ms, xy: [*log_row(ms, xy), round(winding_angle(xy))])


def main(argv=None):
    return generator_main(argv, "winding-shapes", __doc__.split("\n")[0], OUT, SEED, SHAPES, write)

"""The synthesised hand-drawn crossing set ``sosdyn/lfd/data/datasets/crossing`` (issue 28).

``python -m problems crossing-shapes [--out DIR] [--seed 28] [--figure PNG]`` writes, per shape,
``demo_NN.csv`` (``time_ms,x,y``), a ``manifest.csv`` and (``--figure``) an overview PNG.

Nobody can draw with a mouse in the environment where sosdyn is built, so the demonstrations
are synthesised the way a person's mouse strokes come out, from a seeded generator:

1. **Pen path**: the shape's waypoints (:data:`SHAPES`, px, y up, last waypoint = the goal) are
   perturbed per demo — a random size (x ``SCALE``), slant (shear ``SLANT``) and rotation
   (``ROTATE``) about the goal, and an independent offset of every waypoint but the last
   (``JITTER`` x the shape's size) — and joined by a cubic spline in chord length (C2, so the
   curvature is continuous like a pen's).
2. **Speed**: the two-thirds power law of human drawing, speed ~ curvature^(-1/3) (Lacquaniti,
   Terzuolo & Viviani 1983), capped, times a smooth onset and landing (the first and last
   :data:`RAMP` of the path) so the pen starts slowly and stops at the goal; the mean speed per
   demo is ``SPEED`` px/s x a random factor.
3. **Logger**: events every ``EVENT_MS`` ms with jitter (integer ms), positions rounded to integer
   pixels, a rest at the start and at the end (repeated samples, as a mouse logger records a
   still hand). The goal is the origin: every demo ends at (0, 0), as in LASA.
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.report.figures.style import new_figure

OUT = DATASETS_DIR / "crossing"
SEED = 28
SCALE, SLANT, ROTATE, JITTER = 0.07, 0.08, np.radians(4.0), 0.018
SPEED, RAMP, EVENT_MS = 260.0, 0.12, (10.0, 2.5)
REST_START_MS, REST_END_MS = (120, 400), (300, 700)

#: Shape name -> (description, waypoint lists (one per family), demos per family). px, y up.
SHAPES = {
    "ell": ("a cursive l: up-stroke to the right, loop at the top, stem down across the up-stroke, exit right",
            [[(-140, -30), (-60, 20), (10, 120), (35, 220), (10, 285), (-25, 250), (-25, 150), (-15, 60),
              (5, 5), (50, -15), (100, 0)]], 7),
    "e": ("a cursive e: entry stroke to the right, loop up and back, down across the entry, exit right",
          [[(-130, -10), (-40, 15), (50, 50), (65, 100), (30, 135), (-25, 120), (-55, 70), (-45, 10),
            (-10, -30), (50, -40), (110, -15)]], 7),
    "phi": ("a phi: stem from the top down, loop round the stem (crossing it twice), stem down to the goal",
            [[(-10, 210), (0, 130), (0, 40), (10, -20), (60, -15), (80, 40), (55, 95), (0, 105), (-55, 85),
              (-75, 30), (-50, -20), (-10, -50), (0, -120), (0, -180)]], 7),
    "alpha": ("an alpha: from the upper right down-left, round the bowl, back across to the lower right",
              [[(130, 90), (40, 20), (-20, -35), (-80, -30), (-100, 25), (-70, 70), (-15, 65), (45, 15),
                (110, -50), (150, -70)]], 7),
    "gamma": ("a gamma: down-right stroke to a loop at the bottom, back up-right across the down-stroke",
              [[(-90, 170), (-30, 60), (5, -30), (15, -110), (0, -150), (-20, -115), (-5, -30), (35, 60),
                (90, 150)]], 7),
    "at": ("an @: a small a-loop, stem, a large loop round it, then in across the a-loop to the goal",
           [[(45, 20), (20, 55), (-30, 50), (-50, 0), (-25, -45), (25, -40), (50, 0), (60, -55), (110, -40),
             (140, 30), (100, 120), (0, 150), (-110, 110), (-150, 0), (-100, -110), (10, -140), (90, -100),
             (60, -40), (0, 0)]], 7),
    "pretzel": ("a pretzel: up into a left loop, across the middle, a right loop, across again, down",
                [[(-150, -90), (-60, 0), (30, 90), (100, 110), (130, 50), (80, 0), (0, -5), (-80, 0),
                  (-130, 50), (-100, 110), (-30, 90), (60, 0), (150, -90)]], 7),
    "cross": ("two families from left and right that pass each other head-on and curl down to the goal",
              [[(-230, 160), (-120, 165), (0, 150), (100, 120), (160, 40), (120, -50), (50, -90), (0, -100)],
               [(230, 180), (120, 170), (0, 130), (-100, 100), (-160, 20), (-120, -60), (-50, -95), (0, -100)]],
              8),
}


def pen_path(waypoints, rng) -> np.ndarray:
    """Step 1: the perturbed waypoints (goal kept), translated so the goal is the origin,
    joined by a chord-length cubic spline; 4000 points along it."""
    W = np.asarray(waypoints, dtype=float)
    W = W - W[-1]
    size = float(np.linalg.norm(W.max(axis=0) - W.min(axis=0)))
    W[:-1] += rng.normal(scale=JITTER * size, size=W[:-1].shape)
    a, shear = rng.normal(scale=ROTATE), rng.normal(scale=SLANT)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) @ np.array([[1.0, shear], [0.0, 1.0]])
    W = (W @ R.T) * (1 + rng.normal(scale=SCALE, size=2) * [1, 0.5] + rng.normal(scale=SCALE))
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))])
    return CubicSpline(s, W, bc_type="natural")(np.linspace(0, s[-1], 4000))


def timing(path: np.ndarray, speed: float) -> np.ndarray:
    """Step 2: the time (s) at each point of ``path``: speed ~ kappa^(-1/3) (capped at 3x the
    median), times the onset / landing ramp sin^2 over the first and last RAMP of arc length,
    scaled to mean speed ``speed``."""
    d1, d2 = np.gradient(path, axis=0), np.gradient(np.gradient(path, axis=0), axis=0)
    ds = np.linalg.norm(d1, axis=1)
    kappa = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(ds, 1e-12) ** 3
    v = np.minimum(np.maximum(kappa, 1e-6) ** (-1 / 3), 3 * np.median(kappa ** (-1 / 3)))
    u = np.concatenate([[0.0], np.cumsum(ds[1:])]) / ds[1:].sum()
    ramp = np.sin(0.5 * np.pi * np.clip(np.minimum(u, 1 - u) / RAMP, 0.0, 1.0)) ** 2
    v = v * np.maximum(ramp, 0.04)
    t = np.concatenate([[0.0], np.cumsum(ds[1:] / (0.5 * (v[1:] + v[:-1])))])
    return t * (t[-1] and (ds[1:].sum() / t[-1]) / speed)


def log_samples(path: np.ndarray, t: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: (time_ms, integer positions) of a mouse logger watching the pen."""
    rest0, rest1 = rng.integers(*REST_START_MS), rng.integers(*REST_END_MS)
    total = rest0 + 1000 * t[-1] + rest1
    stamps = [0]
    while stamps[-1] < total:
        stamps.append(stamps[-1] + max(4, int(round(rng.normal(*EVENT_MS)))))
    ms = np.array(stamps)
    tau = np.clip((ms - rest0) / 1000.0, 0.0, t[-1])
    xy = np.column_stack([np.interp(tau, t, path[:, k]) for k in range(2)])
    return ms, np.rint(xy).astype(int)


def generate(seed: int = SEED, shapes: dict = SHAPES) -> dict:
    """{shape: [(time_ms, xy) per demo]} of ``shapes`` (as :data:`SHAPES`), families interleaved (A, B, A, B, ...)."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, (_, families, n) in shapes.items():
        demos = []
        for k in range(n):
            path = pen_path(families[k % len(families)], rng)
            demos.append(log_samples(path, timing(path, SPEED * np.exp(rng.normal(scale=0.15))), rng))
        out[name] = demos
    return out


def write_set(data: dict, out_dir: Path, columns: list[str], row_of, lines=None) -> None:
    """The CSVs of ``data`` ({shape: [(time_ms, xy)]}) and one manifest: file, then ``columns``,
    their values ``row_of(shape, k, time_ms, xy)`` for demo k. A CSV's lines are ``lines(time_ms, xy)``
    (default: the numbers as they are, integers for a mouse log)."""
    rows = []
    for name, demos in data.items():
        folder = Path(out_dir) / name
        folder.mkdir(parents=True, exist_ok=True)
        for k, (ms, xy) in enumerate(demos):
            file = f"demo_{k:02d}.csv"
            with open(folder / file, "w", newline="") as handle:
                w = csv.writer(handle)
                w.writerow(["time_ms", "x", "y"])
                w.writerows(np.column_stack([ms, xy]).tolist() if lines is None else lines(ms, xy))
            rows.append([f"{name}/{file}", *row_of(name, k, ms, xy)])
    with open(Path(out_dir) / "manifest.csv", "w", newline="") as handle:
        w = csv.writer(handle)
        w.writerow(["file", *columns])
        w.writerows(rows)


#: The manifest's columns after file and family: samples, duration, start and end point.
LOG_COLUMNS = ["samples", "duration_ms", "start_x", "start_y", "end_x", "end_y"]


def log_row(ms: np.ndarray, xy: np.ndarray) -> list:
    """The values of :data:`LOG_COLUMNS` of one logged demo."""
    return [len(ms), int(ms[-1]), *xy[0], *xy[-1]]


def write(data: dict, out_dir: Path) -> None:
    """The CSVs and one manifest for all shapes (file, family, samples, duration, start, end)."""
    write_set(data, out_dir, ["family", *LOG_COLUMNS],
              lambda name, k, ms, xy: ["AB"[k % len(SHAPES[name][1])], *log_row(ms, xy)])


def overview(data: dict, png: Path, shapes: dict = SHAPES) -> Path:
    """All shapes, one panel each, demos as logged (px), coloured by family."""
    fig = new_figure(16, 8)
    for i, (name, demos) in enumerate(data.items()):
        ax = fig.add_subplot(2, (len(data) + 1) // 2, i + 1)
        for k, (_, xy) in enumerate(demos):
            ax.plot(xy[:, 0], xy[:, 1], lw=0.8, color=("#0072B2", "#D55E00")[k % len(shapes[name][1])])
            ax.plot(*xy[0], "o", ms=3, color="0.3")
        ax.plot(0, 0, "*", ms=10, color="black")
        ax.set_title(name)
        ax.set_aspect("equal")
    fig.savefig(png, dpi=72)
    return png


def generator_main(argv, name: str, description: str, out: Path, seed: int, shapes: dict, write_set,
                   make=None) -> int:
    """The command line of a set generator ``python -m problems NAME [--out DIR] [--seed S] [--figure PNG]``:
    ``make(seed, shapes)`` (default :func:`generate`), ``write_set(data, out)`` and (``--figure``)
    :func:`overview` (the families of ``shapes``)."""
    p = argparse.ArgumentParser(prog=f"python -m problems {name}", description=description)
    p.add_argument("--out", type=Path, default=out, help="output folder (default: the shipped set)")
    p.add_argument("--seed", type=int, default=seed)
    p.add_argument("--figure", type=Path, default=None, help="also write an overview PNG here")
    args = p.parse_args(list(argv or []))
    data = (make or generate)(args.seed, shapes)
    write_set(data, args.out)
    if args.figure:
        overview(data, args.figure, shapes)
    print(f"{name}: {len(data)} shapes, {sum(map(len, data.values()))} demos -> {args.out}")
    return 0


def main(argv=None):
    return generator_main(argv, "crossing-shapes", __doc__.split("\n")[0], OUT, SEED, SHAPES, write)

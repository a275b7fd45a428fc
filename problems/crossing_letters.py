"""The held-out crossing letters ``sosdyn/lfd/data/datasets/crossing_letters`` (issue 36).

``python -m problems crossing-letters [--out DIR] [--seed 36] [--figure PNG]`` writes, per letter,
``demo_NN.csv`` (``time_ms,x,y``), a ``manifest.csv`` and (``--figure``) an overview PNG.

A second synthetic set of letters that cross, made by a generator that shares nothing with
:mod:`problems.crossing_shapes` (the set the second-order model is tuned on) but the idea of a
pen: other letters, another stroke model, another logger. Models are tuned on the shipped
``crossing`` set only and measured on both.

1. **Stroke model: sigma-lognormal** (Plamondon's kinematic theory of rapid movements; O'Reilly &
   Plamondon 2009). A letter is an action plan: virtual targets P_0..P_m and, per stroke j, an
   angular deviation dtheta_j (the arc it bends through). Stroke j has the speed profile
   |v_j(t)| = D_j lognormal(t - t0_j; mu_j, sigma_j) and the direction
   phi_j(t) = theta_j + dtheta_j Phi((ln(t - t0_j) - mu_j) / sigma_j) (Phi the normal CDF), where
   theta_j and D_j make the isolated stroke a circular arc from P_{j-1} to P_j; the pen's velocity is
   the sum of the overlapping strokes, so the path cuts between the targets the way fast handwriting does.
   Per demo: every target moved by ``TARGET_JITTER`` x the letter's size (the last one too: the
   goal is where the pen stops), each dtheta_j by ``ARC_JITTER``, the stroke onsets, mu_j and sigma_j
   drawn around the plan, the whole letter rotated (``ROTATE``) and scaled (``SCALE``).
2. **Tremor**: a physiological tremor (8-12 Hz, ``TREMOR_PX``) and a slow drift of the hand.
3. **Logger: a pen tablet** (unlike the mouse of ``crossing``): a fixed ``PERIOD_MS`` report period
   with a fraction ``DROP`` of reports lost, positions at the tablet's 0.1 px resolution plus sensor
   noise, the pen resting (hovering noise only) before and after the letter. The last report is moved
   to the origin (the goal) with the whole demo, as in LASA.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.special import erf

from sosdyn.lfd.data.datasets import DATASETS_DIR

from .crossing_shapes import LOG_COLUMNS, generator_main, log_row, write_set

OUT = DATASETS_DIR / "crossing_letters"
SEED = 36
DEMOS = 7
TARGET_JITTER, ARC_JITTER, ROTATE, SCALE = 0.025, np.radians(8.0), np.radians(5.0), 0.08
ONSET, ONSET_JITTER, MU_JITTER, SIGMA = 0.9, 0.06, 0.05, (0.25, 0.03)   # onset spacing (x exp(mu)), its jitter, mu (log), sigma
STROKE_S = 0.30                                                 # typical stroke duration exp(mu)
TREMOR_PX, TREMOR_HZ, DRIFT_PX = 0.35, (8.0, 12.0), 1.5
PERIOD_MS, DROP, NOISE_PX = 5, 0.04, 0.15
REST_START_MS, REST_END_MS = (60, 250), (200, 500)

#: Letter -> (description, action plan [(x, y, dtheta_deg) per target; the first target's angle is unused]).
#: Targets in px (y up); dtheta > 0 bends the stroke counter-clockwise.
LETTERS = {
    "b": ("a cursive b: up-stroke, loop at the top, stem down across it, bowl and a tie to the right",
          [(-80, -90, 0), (10, 60, -40), (-10, 160, 170), (-45, -95, -10), (40, -40, 120), (-25, -60, 60),
           (60, -70, -40)]),
    "h": ("a cursive h: up-stroke to a tall loop, stem down across it, a hump and down to the right",
          [(-90, -100, 0), (0, 70, -40), (-20, 180, 160), (-40, -100, -10), (30, -10, -150), (60, -100, 0),
           (100, -85, 60)]),
    "f": ("a cursive f: up into a top loop, a long stem down, a lower loop back up across the stem",
          [(-70, 20, 0), (10, 150, -50), (-10, 220, 170), (-20, -150, 0), (40, -110, 170), (-10, 10, 60),
           (80, 0, -30)]),
    "g": ("a cursive g: a bowl, the stem down, a descender loop back up across the stem",
          [(40, 60, 0), (-40, 50, 150), (-40, -10, 110), (40, 40, 150), (30, -160, 10), (-40, -130, -170),
           (60, -30, 30), (110, -10, 0)]),
    "eight": ("an 8: over the top to the left, down across the waist, round the lower loop, back up across it",
              [(50, 210, 0), (-40, 200, 90), (40, 100, 40), (-50, -20, -40), (40, -10, -150), (-30, 90, -30),
               (0, 140, 40)]),
    "four": ("a 4 in one stroke: down-left diagonal, a bar to the right across the stem, the stem down across the bar",
             [(40, 200, 0), (-80, 40, 0), (90, 40, 10), (60, 120, 80), (40, -100, 0)]),
}


def lognormal_speed(t: np.ndarray, t0: float, mu: float, sigma: float) -> np.ndarray:
    """The unit-area lognormal profile of onset t0 (0 before it)."""
    s = np.maximum(t - t0, 1e-12)
    return np.where(t > t0, np.exp(-(np.log(s) - mu) ** 2 / (2 * sigma ** 2)) / (sigma * np.sqrt(2 * np.pi) * s), 0.0)


def lognormal_cdf(t: np.ndarray, t0: float, mu: float, sigma: float) -> np.ndarray:
    s = np.maximum(t - t0, 1e-12)
    return np.where(t > t0, 0.5 * (1 + erf((np.log(s) - mu) / (sigma * np.sqrt(2)))), 0.0)


def stroke_plan(plan, rng) -> list[tuple]:
    """Step 1: one demo's strokes (t0, mu, sigma, D, theta_start, dtheta) from the perturbed plan."""
    P = np.array([p[:2] for p in plan], dtype=float)
    size = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    P += rng.normal(scale=TARGET_JITTER * size, size=P.shape)
    a = rng.normal(scale=ROTATE)
    P = P @ np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]]) * np.exp(rng.normal(scale=SCALE))
    strokes, t0 = [], 0.0
    for j in range(1, len(P)):
        dth = np.radians(plan[j][2]) + rng.normal(scale=ARC_JITTER)
        chord = P[j] - P[j - 1]
        c = float(np.linalg.norm(chord))
        D = c if abs(dth) < 1e-6 else c * (dth / 2) / np.sin(dth / 2)
        theta = np.arctan2(chord[1], chord[0]) - dth / 2
        mu = np.log(STROKE_S * (c / 150.0) ** 0.3) + rng.normal(scale=MU_JITTER)
        sigma = max(0.12, rng.normal(*SIGMA))
        strokes.append((t0, mu, sigma, D, theta, dth))
        t0 += np.exp(mu) * (ONSET + rng.normal(scale=ONSET_JITTER))
    return strokes


def pen_velocity(strokes, t: np.ndarray) -> np.ndarray:
    """The summed stroke velocities (T, 2) at times t (the sigma-lognormal model)."""
    v = np.zeros((len(t), 2))
    for t0, mu, sigma, D, theta, dth in strokes:
        speed = D * lognormal_speed(t, t0, mu, sigma)
        phi = theta + dth * lognormal_cdf(t, t0, mu, sigma)
        v += speed[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
    return v


def pen_path(strokes, rng, dt: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """(t, xy) of the pen at 1 ms: the integrated velocity (until every stroke has ended), plus tremor and drift."""
    end = max(t0 + np.exp(mu + 3.5 * s) for t0, mu, s, *_ in strokes)
    t = np.arange(0.0, end, dt)
    xy = np.cumsum(pen_velocity(strokes, t), axis=0) * dt
    f, ph = rng.uniform(*TREMOR_HZ), rng.uniform(0, 2 * np.pi, 2)
    tremor = TREMOR_PX * np.column_stack([np.sin(2 * np.pi * f * t + ph[0]), np.sin(2 * np.pi * f * t + ph[1])])
    drift = DRIFT_PX * np.sin(np.pi * t / t[-1])[:, None] * rng.normal(size=2)
    return t, xy + tremor + drift


def tablet_log(t: np.ndarray, xy: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
    """Step 3: (time_ms, positions at 0.1 px) of a tablet reporting every PERIOD_MS, some reports lost."""
    rest0, rest1 = rng.integers(*REST_START_MS), rng.integers(*REST_END_MS)
    ms = np.arange(0, rest0 + int(1000 * t[-1]) + rest1, PERIOD_MS)
    ms = ms[(rng.random(len(ms)) > DROP) | (ms == 0) | (ms == ms[-1])]
    tau = np.clip((ms - rest0) / 1000.0, 0.0, t[-1])
    pos = np.column_stack([np.interp(tau, t, xy[:, k]) for k in range(2)])
    pos += rng.normal(scale=NOISE_PX, size=pos.shape)
    pos -= pos[-1]
    return ms, np.round(pos, 1)


def generate(seed: int = SEED) -> dict:
    """{letter: [(time_ms, xy) per demo]}."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, (_, plan) in LETTERS.items():
        out[name] = [tablet_log(*pen_path(stroke_plan(plan, rng), rng), rng) for _ in range(DEMOS)]
    return out


def write(data: dict, out_dir: Path) -> None:
    """The CSVs (integer ms, positions at 0.1 px) and one manifest (file, samples, duration, start, end)."""
    write_set(data, out_dir, LOG_COLUMNS, lambda name, k, ms, xy: log_row(ms, xy),
              lines=lambda ms, xy: [[int(m), f"{x:.1f}", f"{y:.1f}"] for m, (x, y) in zip(ms, xy)])


def main(argv=None):
    families = {name: (text, [plan]) for name, (text, plan) in LETTERS.items()}      # one family each
    return generator_main(argv, "crossing-letters", __doc__.split("\n")[0], OUT, SEED, families, write,
                          make=lambda seed, _: generate(seed))

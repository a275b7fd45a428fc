"""Generate ``examples/data/reach/``: the README's "your own robot logs" data set.

Four generated (not recorded) demonstrations of a 3-D reach in metres, as a robot logger
writes them: one CSV per demonstration with the header ``time_ms,x,y,z`` and epoch time
stamps in milliseconds at 100 Hz. Each reach starts near (0.55, 0.20, 0.10) m, lifts about
0.12 m on the way and settles on the goal (0.30, -0.10, 0.25) m in about 2.5 s
(minimum-jerk timing, 0.5 mm noise). Fixed seed; the CSVs are committed, and
``tests/test_readme.py`` checks that this script reproduces them byte for byte::

    python examples/data/make_reach.py [OUT_DIR]
"""
import sys
from pathlib import Path

import numpy as np

SEED = 7
GOAL = np.array([0.30, -0.10, 0.25])         # m
START = np.array([0.55, 0.20, 0.10])
RATE_HZ, N_DEMOS, EPOCH_MS = 100, 4, 1_700_000_000_000


def demo(rng, k: int) -> str:
    duration = rng.uniform(2.3, 2.7)
    t = np.arange(0.0, duration + 1e-9, 1.0 / RATE_HZ)
    tau = t / t[-1]
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5                     # minimum-jerk progress 0 -> 1
    x0 = START + rng.uniform(-0.04, 0.04, 3)
    lift = np.array([0.0, 0.0, rng.uniform(0.10, 0.14)])
    pos = GOAL + (1 - s)[:, None] * (x0 - GOAL) + np.sin(np.pi * s)[:, None] * lift
    pos[:-1] += rng.normal(0.0, 0.0005, (len(t) - 1, 3))
    stamps = EPOCH_MS + 60_000 * k + np.round(1000 * t).astype(np.int64)
    rows = [f"{ms},{x:.5f},{y:.5f},{z:.5f}" for ms, (x, y, z) in zip(stamps, pos)]
    return "\n".join(["time_ms,x,y,z", *rows]) + "\n"


def main(out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(SEED)
    paths = []
    for k in range(N_DEMOS):
        path = out / f"reach_{k + 1}.csv"
        path.write_text(demo(rng, k), encoding="utf-8")
        paths.append(path)
    return paths


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent / "reach")

"""Generate the synthetic 3-D demonstrations in ``problems/data/demo3d/``.

Four generated (not recorded) demonstrations of a reach that lifts over an obstacle and
swings sideways before settling on the goal (distance to the goal is not monotone), 50 Hz,
about 5 s each, minimum-jerk timing, with added Gaussian noise (1 mm) and a slow sinusoidal
wobble (3 mm) imitating the imperfections of demonstrations recorded by guiding a robot
arm. Fixed seed; run once, the CSVs are committed::

    .venv/bin/python problems/data/make_demo3d.py
"""
from pathlib import Path

import numpy as np

SEED = 20240601
GOAL = np.array([300.0, -100.0, 250.0])      # mm
START = np.array([600.0, 200.0, 100.0])
RATE, N_DEMOS = 50.0, 4


def demo(rng):
    duration = rng.uniform(4.6, 5.4)
    t = np.arange(0.0, duration + 1e-9, 1.0 / RATE)
    tau = t / t[-1]
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5                      # minimum-jerk progress
    x0 = START + rng.uniform(-40, 40, 3)
    lift = np.array([0.0, 0.0, rng.uniform(130, 170)])              # over the obstacle
    swing = np.array([rng.uniform(-20, 20), rng.uniform(90, 120), 0.0])
    pos = (GOAL + (1 - s)[:, None] * (x0 - GOAL) + np.sin(np.pi * s)[:, None] * lift
           + (np.sin(2 * np.pi * s) * (1 - s))[:, None] * swing)
    phase = rng.uniform(0, 2 * np.pi, 3)
    tremor = 3.0 * np.sin(2 * np.pi * 0.7 * t[:, None] + phase) * (1 - s)[:, None]
    pos = pos + tremor + rng.normal(0.0, 1.0, pos.shape)
    return t, pos


def main(folder=Path(__file__).parent / "demo3d"):
    rng = np.random.default_rng(SEED)
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(N_DEMOS):
        t, pos = demo(rng)
        rows = np.column_stack([t, pos])
        np.savetxt(folder / f"demo_{i + 1}.csv", rows, delimiter=",", fmt="%.4f",
                   header="t,x1,x2,x3", comments="")
    print(f"wrote {N_DEMOS} demonstrations to {folder}")


if __name__ == "__main__":
    main()

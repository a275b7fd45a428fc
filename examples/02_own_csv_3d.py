"""Your own demonstrations from CSV files: 3-D motions, fitted and certified.

Writes four noisy 3-D demonstrations as CSV (header t,x,y,z; one file per demo; velocities
are estimated on load), reads them back with `sd.load_demos`, fits CDSP and checks it.
Replace the generated files with yours. Usage: python 02_own_csv_3d.py [OUT_DIR]
"""
import sys
import tempfile
from pathlib import Path

import numpy as np

import sosdyn as sd

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="sosdyn-"))
out.mkdir(parents=True, exist_ok=True)

# A reach-and-lower motion towards the goal (0, 0, 0) from four starts, 3 s at 50 Hz, mm.
rng = np.random.default_rng(1)
t = np.linspace(0.0, 3.0, 151)
s = 1 - np.exp(-2.0 * t) * (1 + 2.0 * t)               # smooth 0 -> 1 (critically damped)
paths = []
for k, start in enumerate([[300, 120, 200], [280, -60, 220], [320, 40, 150], [260, 90, 260]]):
    start = np.asarray(start, float)
    arc = np.outer(np.sin(np.pi * s), [0.0, 0.0, 80.0])  # lift on the way
    pos = np.outer(1 - s, start) + arc + rng.normal(0, 0.3, (t.size, 3))
    pos[-1] = 0.0
    path = out / f"demo_{k + 1}.csv"
    np.savetxt(path, np.column_stack([t, pos]), delimiter=",", header="t,x,y,z", comments="",
               fmt="%.4f")
    paths.append(path)

demos = sd.load_demos(paths, units="mm", name="reach3d")
print(f"{demos.name}: {len(demos)} demos, dim {demos.dim}, goal {demos.goal.round(3)}")

model = sd.CDSP(n_components=3, solver_method="ica", random_state=0).fit(demos)
print(model.verification_)
errors = [np.linalg.norm(model.rollout(d.pos[0], duration=6.0).pos[-1] - demos.goal) for d in demos]
print(f"largest distance to the goal after 6 s: {max(errors):.3f} mm")
model.save(out / "reach3d.json")
print(f"certified: {sd.load_model(out / 'reach3d.json').verification_.passed}")

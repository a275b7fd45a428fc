"""Pushes and a moved goal: a certified model recovers from both.

The model contracts for any goal, so after a push (the state jumps by dx) or a goal change
the trajectory converges again. Usage: python 03_pushes_and_goal_changes.py [OUT_DIR]
Needs the `lasa` extra (pip install 'sosdyn[lasa]').
"""
import sys
import tempfile
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import sosdyn as sd

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="sosdyn-"))
out.mkdir(parents=True, exist_ok=True)

demos = sd.load_lasa("Sshape").subsample(4)
model = sd.CDSP(n_components=5, solver_method="ica", random_state=0).fit(demos)
print(f"certified: {model.verification_.passed}")

x0, new_goal = demos[0].pos[0], np.array([10.0, -5.0])
traj = model.rollout(x0, duration=8.0,
                     perturbations=[(1.0, [15.0, 0.0]), (2.5, [0.0, -10.0])],   # (time s, jump mm)
                     goal_changes=[(4.0, new_goal)])                              # (time s, goal mm)
for event in traj.events:
    print("event:", event)
err = np.linalg.norm(traj.pos[-1] - new_goal)
print(f"distance to the moved goal at t = {traj.t[-1]:.1f} s: {err:.3f} mm")

fig = Figure(figsize=(5, 4))
ax = fig.add_subplot()
for d in demos:
    ax.plot(d.pos[:, 0], d.pos[:, 1], color="0.7", lw=1)
ax.plot(traj.pos[:, 0], traj.pos[:, 1], color="C0", label="rollout with pushes")
ax.plot(*demos.goal, "k*", ms=10, label="original goal")
ax.plot(*new_goal, "r*", ms=10, label="goal from t = 4 s")
ax.set(xlabel="x1 (mm)", ylabel="x2 (mm)", aspect="equal")
ax.legend(fontsize=8)
fig.savefig(out / "pushes.png", dpi=120)
print(f"wrote {out / 'pushes.png'}")

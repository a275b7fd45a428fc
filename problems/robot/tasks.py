"""The real Franka demonstrations (RoboTasks, Auddy et al. 2023) mapped into the simulated Panda's
workspace.

Source: ``<data>/<task>/demo_NN.csv`` (header ``t,x,y,z,qw,qx,qy,qz``; 9 demonstrations of 1000
samples at a nominal 60 Hz per task; positions in cm, see the data's README). Only the positions
are used (the simulated gripper keeps pointing down). The map into the simulator's base frame is
one rigid translation for all four tasks, no scaling and no rotation:

    x_sim = x_cm / 100 + t,     t = c_ws - (centre of the box around every sample of the four tasks, m)

with c_ws = :data:`WORKSPACE_CENTRE`, 0.5 m in front of the robot's base, 0.3 m above the floor
(t is rounded to the millimetre). :func:`reachability` checks it with inverse kinematics. The first
:data:`N_TRAIN` demonstrations of a task train, the others are held out for the trials.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import InputError

from ..settings import REPO

TASKS = ("openbox", "bottle2shelf", "platestandingtolying", "pouring")
#: Default data folder: $SOSDYN_ROBOTTASKS, else ../shared/data/robottasks next to the repository.
DEFAULT_DATA = Path(os.environ.get("SOSDYN_ROBOTTASKS", REPO.parent / "shared" / "data" / "robottasks"))
WORKSPACE_CENTRE = np.array([0.5, 0.0, 0.3])
CM = 0.01
N_TRAIN = 5


def missing_data(data_dir) -> str | None:
    """Why the tasks cannot be read from ``data_dir`` (None when they can)."""
    data_dir = Path(data_dir)
    missing = [t for t in TASKS if not sorted((data_dir / t).glob("demo_*.csv"))]
    if missing:
        return (f"the RoboTasks demonstrations are not in {data_dir} (no {missing[0]}/demo_*.csv); "
                "pass --data DIR or set SOSDYN_ROBOTTASKS")
    return None


def read_task(data_dir, task: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """[(t (T,), positions (T, 3) in cm)] of the task's demonstrations, in file order."""
    why = missing_data(data_dir)
    if why:
        raise InputError(f"{why}. Try: --data /path/to/robottasks.")
    out = []
    for path in sorted((Path(data_dir) / task).glob("demo_*.csv")):
        with open(path) as f:
            header = f.readline().strip().split(",")
        cols = [header.index(c) for c in ("t", "x", "y", "z")]
        a = np.loadtxt(path, delimiter=",", skiprows=1, usecols=cols)
        out.append((a[:, 0], a[:, 1:]))
    return out


def workspace_shift(raw: dict) -> np.ndarray:
    """t (3,) of the module docstring from ``{task: read_task(...)}``."""
    X = np.vstack([pos for demos in raw.values() for _, pos in demos]) * CM
    return np.round(WORKSPACE_CENTRE - 0.5 * (X.min(axis=0) + X.max(axis=0)), 3)


def task_demos(raw_task, shift, task: str) -> sd.Demonstrations:
    """All demonstrations of one task in the simulator's frame (m), velocities estimated."""
    return sd.Demonstrations([sd.Demonstration.from_positions(t, pos * CM + shift, f"{task}/demo_{i:02d}")
                              for i, (t, pos) in enumerate(raw_task)], name=task, units="m")


def reachability(sim, demos, every: int = 50) -> dict:
    """Inverse kinematics (gripper down) at every ``every``-th sample of ``demos``: the largest
    position error (m) and the smallest distance of a joint to its limit (deg)."""
    errs, margins = [], []
    for d in demos:
        for x in d.pos[::every]:
            q, err = sim.solve_ik(x)
            errs.append(err)
            margins.append(np.degrees(np.min(np.minimum(q - sim.lo, sim.hi - q))))
    return {"points": len(errs), "max_ik_error_m": float(max(errs)), "min_joint_margin_deg": float(min(margins))}

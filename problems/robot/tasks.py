"""The real Franka demonstrations (RoboTasks, Auddy et al. 2023) mapped into the simulated Panda's
workspace.

Source: the shipped sets ``sd.load_dataset("robottasks/<task>", positions_only=True)`` (9
demonstrations of 1000 samples at a nominal 60 Hz per task; positions in cm, inferred, see the
set's README). Only the positions are used (the simulated gripper keeps pointing down). The map
into the simulator's base frame is one rigid translation for all four tasks, no scaling and no
rotation:

    x_sim = x_cm / 100 + t,     t = c_ws - (centre of the box around every sample of the four tasks, m)

with c_ws = :data:`WORKSPACE_CENTRE`, 0.5 m in front of the robot's base, 0.3 m above the floor
(t is rounded to the millimetre). :func:`reachability` checks it with inverse kinematics. The first
:data:`N_TRAIN` demonstrations of a task train, the others are held out for the trials.
"""
from __future__ import annotations

import numpy as np

import sosdyn as sd

TASKS = ("openbox", "bottle2shelf", "platestandingtolying", "pouring")
WORKSPACE_CENTRE = np.array([0.5, 0.0, 0.3])
CM = 0.01
N_TRAIN = 5


def read_task(task: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """[(t (T,), positions (T, 3) in cm)] of the task's demonstrations, in file order."""
    return [(d.t, d.pos) for d in sd.load_dataset(f"robottasks/{task}", positions_only=True)]


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

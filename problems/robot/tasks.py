"""The real Franka demonstrations (RoboTasks, Auddy et al. 2023) mapped into the simulated Panda's
workspace.

Source: the shipped sets ``sd.load_dataset("robottasks/<task>")`` (9 demonstrations of 1000 samples at
a nominal 60 Hz per task; positions in cm, inferred, see the set's README; orientations as unit
quaternions). Position trials use the positions (the simulated gripper keeps pointing down); pose trials
use both. The map into the simulator's base frame is one rigid translation for all four tasks, no
scaling and no rotation (orientations as recorded, in the same base frame):

    x_sim = x_cm / 100 + t,     t = c_ws - (centre of the box around every sample of the four tasks, m)

with c_ws = :data:`WORKSPACE_CENTRE`, 0.5 m in front of the robot's base, 0.3 m above the floor
(t is rounded to the millimetre). :func:`reachability` checks it with inverse kinematics, pointing down
and with the recorded orientations. The first :data:`N_TRAIN` demonstrations of a task train, the
others are held out for the trials.
"""
from __future__ import annotations

import numpy as np

import sosdyn as sd
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations

from .arm import DOWN, xyzw
from .control import rotation_error

TASKS = ("openbox", "bottle2shelf", "platestandingtolying", "pouring")
WORKSPACE_CENTRE = np.array([0.5, 0.0, 0.3])
CM = 0.01
N_TRAIN = 5


def read_task(task: str) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """[(t (T,), positions (T, 3) in cm, quaternions (T, 4) w x y z)] of the task's demonstrations, in file order."""
    return [(d.t, d.pos, d.quat) for d in sd.load_dataset(f"robottasks/{task}")]


def workspace_shift(raw: dict) -> np.ndarray:
    """t (3,) of the module docstring from ``{task: read_task(...)}``."""
    X = np.vstack([pos for demos in raw.values() for _, pos, _ in demos]) * CM
    return np.round(WORKSPACE_CENTRE - 0.5 * (X.min(axis=0) + X.max(axis=0)), 3)


def task_demos(raw_task, shift, task: str) -> sd.Demonstrations:
    """All demonstrations of one task in the simulator's frame (m), velocities estimated."""
    return sd.Demonstrations([sd.Demonstration.from_positions(t, pos * CM + shift, f"{task}/demo_{i:02d}")
                              for i, (t, pos, _) in enumerate(raw_task)], name=task, units="m")


def task_pose_demos(raw_task, shift, task: str) -> PoseDemonstrations:
    """All demonstrations of one task as poses in the simulator's frame (m, orientations as recorded)."""
    return PoseDemonstrations([PoseDemonstration(t, pos * CM + shift, quat, f"{task}/demo_{i:02d}")
                               for i, (t, pos, quat) in enumerate(raw_task)], name=task, units="m")


def reachability(sim, demos, every: int = 50) -> dict:
    """Inverse kinematics at every ``every``-th sample of the pose ``demos``, gripper down and with the
    recorded orientation: the largest position error (m), orientation error (deg) and the smallest
    distance of a joint to its limit (deg), for each."""
    out = {}
    for kind in ("down", "recorded"):
        errs, turns, margins = [], [], []
        for d in demos:
            for x, quat in zip(d.pos[::every], d.quat[::every]):
                target = xyzw(quat) if kind == "recorded" else DOWN
                q, err = sim.solve_ik(x, target)
                errs.append(err)
                turns.append(float(np.degrees(np.linalg.norm(rotation_error(sim.ee()[1], target)))))
                margins.append(np.degrees(np.min(np.minimum(q - sim.lo, sim.hi - q))))
        out[kind] = {"points": len(errs), "max_ik_error_m": float(max(errs)), "max_ik_angle_deg": max(turns),
                     "min_joint_margin_deg": float(min(margins))}
    return out


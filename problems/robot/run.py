"""``python -m problems robot [--quick] [--out DIR] [--tasks ...]``: learned models drive a simulated
Franka Panda (the CDSP paper's robot experiment, on a simulator).

Per task of the RoboTasks set (:mod:`.tasks`): the position methods (``sd.CDSP()`` and the GMR baseline,
positions in m, every 4th sample of the first five demonstrations; the gripper held pointing down) and the
pose methods (``sd.PoseCDSP()`` and the GMR pose baseline, on the same demonstrations with their orientations,
preprocessed by :func:`~sosdyn.lfd.data.pose_preprocess.preprocess_poses`; :mod:`.methods`) each drive the arm
through :mod:`.trials` from the held-out demonstrations' starts and from random starts, with pushes and a
moved goal (for pose trials: pushes that also twist, goals that also turn). Writes ``results.json``
(``meta`` and one ``trials`` row per trial), the figures, frames and GIF, and the page ``index.html``
(:mod:`.page`) into ``--out`` (default ``reports/robot``; checked before anything is simulated).
``--quick`` (the tests): one task, two starts per kind, no GIF.
"""
from __future__ import annotations

import argparse
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import InputError
from sosdyn.lfd.data.pose_preprocess import preprocess_poses
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations, goal_orientation

from ..jsonio import write_json
from ..settings import REPORTS, SEED
from . import arm, trials
from .arm import PandaSim, wxyz
from .frames import FrameRecorder
from .methods import POSE_METHODS, POSITION_METHODS, fit
from .page import write_page
from .tasks import N_TRAIN, TASKS, WORKSPACE_CENTRE, reachability, read_task, task_demos, task_pose_demos, \
    workspace_shift

SUBSAMPLE = 4
N_RANDOM = 2
METHODS = POSITION_METHODS + POSE_METHODS
SHOWCASE = ("CDSP", "PoseCDSP")          # the methods whose first pushed, goal-moved trial is filmed


def parse_args(argv) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m problems robot", description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="one task, two starts, no GIF (the tests; < 1 min)")
    p.add_argument("--out", type=Path, default=REPORTS / "robot", help="output folder (default reports/robot)")
    p.add_argument("--tasks", nargs="*", default=None, choices=TASKS, help="tasks (default all four)")
    return p.parse_args(list(argv or []))


def check_out(out_dir: Path) -> Path:
    """``out_dir`` created and writable, before any trial runs (InputError otherwise: a file there, no
    permission)."""
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"--out {out_dir} is a file; the robot run writes a folder (results.json, index.html, "
                         "figures/). Try: --out a folder, e.g. reports/robot.")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        probe = out_dir / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise InputError(f"--out {out_dir} cannot be written ({exc.strerror}). Try: a folder you may write.") from None
    return out_dir


def pose_train(poses: PoseDemonstrations) -> PoseDemonstrations:
    """The pose methods' training data: demos 0..N_TRAIN-1 preprocessed, every SUBSAMPLE-th sample."""
    ready, _ = preprocess_poses(poses[:N_TRAIN])
    return PoseDemonstrations([PoseDemonstration(d.t[::SUBSAMPLE], d.pos[::SUBSAMPLE], d.quat[::SUBSAMPLE], d.source)
                               for d in ready], ready.name, ready.units)


def run(out_dir, *, quick=False, tasks=None) -> dict:
    out_dir = check_out(out_dir)
    tasks = tasks or (TASKS[:1] if quick else TASKS)
    raw = {t: read_task(t) for t in TASKS}
    shift = workspace_shift(raw)
    rng = np.random.default_rng(SEED)
    sim = PandaSim()
    rows, paths, fits, reach, demos_of, showcase = [], {}, {}, {}, {}, {}
    for task in tasks:
        demos, poses = task_demos(raw[task], shift, task), task_pose_demos(raw[task], shift, task)
        demos_of[task] = demos
        reach[task] = reachability(sim, poses)
        train = {"position": demos[:N_TRAIN].subsample(SUBSAMPLE), "pose": pose_train(poses)}
        duration = 2.0 * float(np.mean([d.duration for d in demos]))
        test_ids = [len(demos) - 1] if quick else range(N_TRAIN, len(demos))
        goal = np.concatenate([demos.goal, wxyz(arm.DOWN)])
        specs = {kind: trials.trial_specs(task, poses, test_ids, rng, 1 if quick else N_RANDOM, duration,
                                          pose=kind == "pose") for kind in ("position", "pose")}
        for name in METHODS:
            kind = "pose" if name in POSE_METHODS else "position"
            command, fits[f"{task}/{name}"] = fit(name, train[kind])
            goal0 = goal if kind == "position" else np.concatenate([train[kind].goal_pos, goal_orientation(train[kind])])
            for i, spec in enumerate(specs[kind]):
                recorder = None
                if name in SHOWCASE and name not in showcase and spec.push and spec.goal_move:
                    recorder = FrameRecorder(demos[spec.demo].pos if spec.demo is not None else None,
                                             spec.push[1], gif=not quick)
                t0 = time.perf_counter()
                row, path = trials.run_trial(sim, command, goal0, spec, on_step=recorder)
                row["method"] = name
                row["path_deviation_m"] = (None if spec.demo is None else
                                           trials.path_deviation(path["x"], demos[spec.demo].pos))
                row["wall_time_s"] = time.perf_counter() - t0
                rows.append(row)
                paths[(task, name, i)] = path
                if recorder is not None:
                    showcase[name] = {"row": row, "recorder": recorder}
                print(f"robot {task} {name} start {row['start']}{'' if spec.demo is None else spec.demo} "
                      f"push {row['push']} goal moved {row['goal_moved']}: "
                      f"{'success' if row['success'] else 'FAIL'}, error {1e3 * row['final_pos_err_m']:.2f} mm "
                      f"{row['final_ori_err_deg']:.2f} deg, time to goal {row['time_to_goal_s']}, "
                      f"({row['wall_time_s']:.1f} s)", flush=True)
    sim.close()
    meta = {"simulator": f"pybullet {version('pybullet')} (Bullet physics, headless p.DIRECT, TinyRenderer)",
            "robot": f"Franka Emika Panda, pybullet_data {arm.URDF}, end effector link {arm.EE_LINK} "
                     "(panda_grasptarget); position trials hold the gripper pointing down, pose trials follow the "
                     "model's angular velocity",
            "versions": {"sosdyn": sd.__version__, "pybullet": version("pybullet"), "numpy": np.__version__},
            "quick": quick, "seed": SEED, "rate_hz": arm.RATE, "control": "joint VELOCITY_CONTROL, "
            "damped least squares on the 6-D Jacobian, null-space joint-limit avoidance",
            "max_speed_m_s": trials.MAX_SPEED, "max_angular_speed_rad_s": trials.MAX_ANGULAR_SPEED,
            "success_tol_m": trials.TOL, "success_tol_deg": trials.ORI_TOL_DEG,
            "push": {"force_n": trials.PUSH_FORCE, "torque_nm": trials.PUSH_TORQUE,
                     "duration_s": trials.PUSH_STEPS / arm.RATE},
            "goal_shift_m": trials.GOAL_SHIFT, "goal_turn_deg": trials.GOAL_TURN_DEG,
            "data": {"source": "sd.load_dataset('robottasks/<task>'): RoboTasks (Auddy et al. 2023), positions in cm, "
                               "orientations (unit quaternions)",
                     "train": f"demos 0-{N_TRAIN - 1}, every {SUBSAMPLE}th sample (pose methods: preprocessed first)",
                     "test": f"demos {N_TRAIN}-8 (starts)"},
            "transform": {"formula": "x_sim = x_cm / 100 + shift", "shift_m": shift,
                          "workspace_centre_m": WORKSPACE_CENTRE},
            "reachability": reach, "fits": fits}
    results = {"meta": meta, "trials": rows}
    write_json(out_dir / "results.json", results)
    write_page(out_dir, results, paths, demos_of, showcase)
    return results


def main(argv=None):
    args = parse_args(argv)
    t0 = time.perf_counter()
    results = run(args.out, quick=args.quick, tasks=args.tasks)
    rows = results["trials"]
    for name in METHODS:
        mine = [r for r in rows if r["method"] == name]
        print(f"{name}: {sum(r['success'] for r in mine)}/{len(mine)} trials succeeded")
    print(f"robot: {Path(args.out) / 'index.html'} ({time.perf_counter() - t0:.0f} s)")
    return 0

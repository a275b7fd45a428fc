"""``python -m problems robot [--quick] [--out DIR] [--tasks ...]``: learned models drive a simulated
Franka Panda (the CDSP paper's robot experiment, on a simulator).

Per task of the RoboTasks set (:mod:`.tasks`): ``sd.CDSP()`` and the GMR baseline are fitted on
the first five demonstrations (positions in m, every 4th sample); each drives the arm through
:mod:`.trials` from the held-out demonstrations' starts and from random starts, with pushes and a
moved goal. Writes ``results.json`` (``meta`` and one ``trials`` row per trial), the figures, frames
and GIF, and the page ``index.html`` (:mod:`.page`) into ``--out`` (default ``reports/robot``).
``--quick`` (the tests): one task, two starts, no GIF.
"""
from __future__ import annotations

import argparse
import time
from functools import partial
from importlib.metadata import version
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.evaluation.baselines import GMR
from sosdyn.lfd.runtime.states import limit_speed

from ..jsonio import write_json
from ..settings import REPORTS, SEED
from . import arm, trials
from .arm import PandaSim
from .frames import FrameRecorder
from .page import write_page
from .tasks import N_TRAIN, TASKS, WORKSPACE_CENTRE, reachability, read_task, task_demos, \
    workspace_shift

SUBSAMPLE = 4
N_RANDOM = 2
METHODS = ("CDSP", "GMR")


def parse_args(argv) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m problems robot", description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="one task, two starts, no GIF (the tests; < 1 min)")
    p.add_argument("--out", type=Path, default=REPORTS / "robot", help="output folder (default reports/robot)")
    p.add_argument("--tasks", nargs="*", default=None, choices=TASKS, help="tasks (default all four)")
    return p.parse_args(list(argv or []))


def gmr_step(model, max_speed, x, goal):
    """GMR's xdot at x for the goal (its field translated there), scaled to |xdot| <= max_speed
    as CDSP's ``predictor(max_speed=...)`` does."""
    return limit_speed(model.field(x[None], goal), max_speed)[0]


def fit(name, train):
    """(fitted model, command (x, goal) -> xdot, fit record) of method ``name``."""
    t0 = time.perf_counter()
    if name == "CDSP":
        model = sd.CDSP(random_state=SEED).fit(train)
        command = model.predictor(max_speed=trials.MAX_SPEED)             # step(x, goal)
        record = {"certified": bool(model.certified_), "warp": model.warp_ is not None}
    else:
        model = GMR(random_state=SEED).fit(train)
        command = partial(gmr_step, model, trials.MAX_SPEED)
        record = {}
    return model, command, dict(record, fit_time_s=time.perf_counter() - t0)


def run(out_dir, *, quick=False, tasks=None) -> dict:
    out_dir = Path(out_dir)
    tasks = tasks or (TASKS[:1] if quick else TASKS)
    raw = {t: read_task(t) for t in TASKS}
    shift = workspace_shift(raw)
    rng = np.random.default_rng(SEED)
    sim = PandaSim()
    rows, paths, fits, reach, demos_of, showcase = [], {}, {}, {}, {}, None
    for task in tasks:
        demos = task_demos(raw[task], shift, task)
        demos_of[task] = demos
        reach[task] = reachability(sim, demos)
        train = demos[:N_TRAIN].subsample(SUBSAMPLE)
        duration = 2.0 * float(np.mean([d.duration for d in demos]))
        test_ids = [len(demos) - 1] if quick else range(N_TRAIN, len(demos))
        specs = trials.trial_specs(task, demos, test_ids, rng, 1 if quick else N_RANDOM, duration)
        for name in METHODS:
            _, command, fits[f"{task}/{name}"] = fit(name, train)
            for i, spec in enumerate(specs):
                recorder = None
                if showcase is None and name == "CDSP" and spec.push and spec.goal_move:
                    recorder = FrameRecorder(demos[spec.demo].pos if spec.demo is not None else None,
                                             spec.push[1], gif=not quick)
                t0 = time.perf_counter()
                row, path = trials.run_trial(sim, command, demos.goal, spec, on_step=recorder)
                row["method"] = name
                row["path_deviation_m"] = (None if spec.demo is None else
                                           trials.path_deviation(path["x"], demos[spec.demo].pos))
                row["wall_time_s"] = time.perf_counter() - t0
                rows.append(row)
                paths[(task, name, i)] = path
                if recorder is not None:
                    showcase = {"row": row, "recorder": recorder}
                print(f"robot {task} {name} start {row['start']}{'' if spec.demo is None else spec.demo} "
                      f"push {row['push']} goal moved {row['goal_moved']}: "
                      f"{'success' if row['success'] else 'FAIL'}, error {1e3 * row['final_pos_err_m']:.2f} mm, "
                      f"time to goal {row['time_to_goal_s']}, ({row['wall_time_s']:.1f} s)", flush=True)
    sim.close()
    meta = {"simulator": f"pybullet {version('pybullet')} (Bullet physics, headless p.DIRECT, TinyRenderer)",
            "robot": f"Franka Emika Panda, pybullet_data {arm.URDF}, end effector link {arm.EE_LINK} "
                     "(panda_grasptarget), gripper held pointing down",
            "versions": {"sosdyn": sd.__version__, "pybullet": version("pybullet"), "numpy": np.__version__},
            "quick": quick, "seed": SEED, "rate_hz": arm.RATE, "control": "joint VELOCITY_CONTROL, "
            "damped least squares on the 6-D Jacobian, null-space joint-limit avoidance",
            "max_speed_m_s": trials.MAX_SPEED, "success_tol_m": trials.TOL,
            "push": {"force_n": trials.PUSH_FORCE, "duration_s": trials.PUSH_STEPS / arm.RATE},
            "goal_shift_m": trials.GOAL_SHIFT,
            "data": {"source": "sd.load_dataset('robottasks/<task>'): RoboTasks (Auddy et al. 2023), positions in cm",
                     "train": f"demos 0-{N_TRAIN - 1}, every {SUBSAMPLE}th sample",
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

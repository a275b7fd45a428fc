"""Trials of a learned motion model driving the simulated arm (:class:`.arm.PandaSim`).

A trial starts the gripper at x0 (inverse kinematics, at rest), then at every simulator step
(240 Hz) reads the end effector x and the current goal g(t), asks the model for
xdot = f_g(x) with its speed limited to |xdot| <= v_max (``model.predictor(max_speed=v_max)``,
``step(x, goal)``) and sends the joint velocities of :mod:`.control`. Disturbances: a push (a force on the end effector for :data:`PUSH_STEPS` steps)
and a goal moved once by a few cm (the red marker moves with it). Measured per trial: the final
distance to the current goal, the time from which the gripper stays within :data:`TOL` of it,
whether a joint came within 0.5 deg of a limit, the peak joint speed (measured: a push can spin the
wrist faster than the controller may; and commanded), the largest displacement the push caused,
and for starts from a held-out demonstration the path's mean distance to that demonstration.
Success: within :data:`TOL` of the current goal at the end and no joint limit hit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .arm import DOWN, RATE
from .control import rotation_error

TOL = 0.005                     # success radius (m)
MAX_SPEED = 0.25                # end-effector speed limit (m/s)
PUSH_FORCE = 125.0              # N, horizontal, for PUSH_STEPS steps: a 6.25 N s shove
PUSH_STEPS = 12                 # 0.05 s at 240 Hz
GOAL_SHIFT = 0.04               # m
PUSH_WINDOW = (0.1, 0.3)        # push times: uniform in these fractions of the demos' duration
GOAL_WINDOW = (0.25, 0.45)      # goal-move times: the same
PATH_EVERY = 8                  # path samples kept: 30 Hz


@dataclass(frozen=True)
class TrialSpec:
    """One trial: task, start, the held-out demo it starts from (index) or None (a random start),
    the push (time s, force N (3,)) or None, the goal move (time s, shift m (3,)) or None, duration s."""

    task: str
    start: np.ndarray
    demo: int | None
    push: tuple[float, np.ndarray] | None
    goal_move: tuple[float, np.ndarray] | None
    duration: float


def trial_specs(task, demos, test_ids, rng, n_random, duration) -> list[TrialSpec]:
    """The held-out demonstrations' starts cycle through (push and goal moved, neither, push, goal moved);
    ``n_random`` starts drawn uniformly in the box of the task's demos (grown by 5 cm, z >= 0.1 m)
    get both. Push and goal-move times: uniform in :data:`PUSH_WINDOW` / :data:`GOAL_WINDOW`."""
    X = np.vstack([d.pos for d in demos])
    lo, hi = X.min(axis=0) - 0.05, X.max(axis=0) + 0.05
    lo[2] = max(lo[2], 0.1)
    t_demo = float(np.mean([d.duration for d in demos]))
    conditions = [(True, True), (False, False), (True, False), (False, True)]

    def spec(start, demo, push, move):
        angle = rng.uniform(0, 2 * np.pi)
        direction = rng.normal(size=3)
        return TrialSpec(task, start, demo,
                         (rng.uniform(*PUSH_WINDOW) * t_demo, PUSH_FORCE * np.array([np.cos(angle), np.sin(angle), 0.0]))
                         if push else None,
                         (rng.uniform(*GOAL_WINDOW) * t_demo, GOAL_SHIFT * direction / np.linalg.norm(direction))
                         if move else None, duration)

    specs = [spec(demos[i].pos[0], i, *conditions[k % 4]) for k, i in enumerate(test_ids)]
    return specs + [spec(rng.uniform(lo, hi), None, True, True) for _ in range(n_random)]


def run_trial(sim, command, goal0, spec: TrialSpec, *, on_step=None) -> tuple[dict, dict]:
    """Drive the arm with ``command(x, goal) -> xdot`` (speed-limited) from ``spec.start``;
    (measurements, path).

    ``on_step(k, t, sim, event)`` (optional) is called every step; ``event`` is "start", "push",
    "goal" (the first step of a disturbance) or None."""
    q0, ik_err = sim.solve_ik(spec.start)
    goal = np.array(goal0, dtype=float)
    sim.reset(q0, goal)
    n = int(round(spec.duration * RATE))
    k_push = None if spec.push is None else int(round(spec.push[0] * RATE))
    k_goal = None if spec.goal_move is None else int(round(spec.goal_move[0] * RATE))
    ts, xs, gs = np.arange(n + 1) / RATE, np.empty((n + 1, 3)), np.empty((n + 1, 3))
    peak_qdot, peak_cmd, hit, push_disp, x_push = 0.0, 0.0, False, 0.0, None
    for k in range(n):
        x, _ = sim.ee()
        event = "start" if k == 0 else None
        if k == k_goal:
            goal = goal + spec.goal_move[1]
            sim.move_marker(goal)
            event = "goal"
        if k_push is not None and k_push <= k < k_push + PUSH_STEPS:
            sim.push(spec.push[1])
            if k == k_push:
                x_push, event = x, "push"
        if x_push is not None and k < k_push + 2 * int(RATE):
            push_disp = max(push_disp, float(np.linalg.norm(x - x_push)))
        xs[k], gs[k] = x, goal
        if on_step is not None:
            on_step(k, ts[k], sim, event)
        qdot_cmd = sim.command(command(x, goal))
        peak_cmd = max(peak_cmd, float(np.abs(qdot_cmd).max()))
        sim.step()
        q, qdot = sim.joints()
        peak_qdot = max(peak_qdot, float(np.abs(qdot).max()))
        hit = hit or sim.at_limit(q)
    x, quat = sim.ee()
    xs[n], gs[n] = x, goal
    if on_step is not None:
        on_step(n, ts[n], sim, "end")
    err = np.linalg.norm(xs - gs, axis=1)
    row = {"method": None, "task": spec.task, "start": "demo" if spec.demo is not None else "random",
           "demo": spec.demo, "push": spec.push is not None, "goal_moved": spec.goal_move is not None,
           "success": bool(err[-1] < TOL and not hit), "final_pos_err_m": float(err[-1]),
           "final_ori_err_deg": None, "time_to_goal_s": time_to_goal(ts, err, TOL),
           "joint_limit_hit": hit, "peak_joint_speed_rad_s": peak_qdot, "peak_commanded_joint_speed_rad_s": peak_cmd,
           "final_tilt_deg": float(np.degrees(np.linalg.norm(rotation_error(quat, DOWN)))),
           "push_time_s": None if spec.push is None else spec.push[0],
           "push_force_n": None if spec.push is None else spec.push[1].tolist(),
           "push_displacement_m": push_disp if spec.push is not None else None,
           "goal_move_time_s": None if spec.goal_move is None else spec.goal_move[0],
           "goal_shift_m": None if spec.goal_move is None else spec.goal_move[1].tolist(),
           "start_ik_error_m": ik_err, "duration_s": spec.duration}
    return row, {"t": ts[::PATH_EVERY], "x": xs[::PATH_EVERY], "goal": gs[::PATH_EVERY]}


def time_to_goal(t, err, tol) -> float | None:
    """The first time from which err stays below tol to the end (None if it does not end there)."""
    outside = np.flatnonzero(err >= tol)
    if outside.size == 0:
        return float(t[0])
    return None if outside[-1] == len(err) - 1 else float(t[outside[-1] + 1])


def path_deviation(path, demo_pos) -> float:
    """Mean distance (m) from each point of ``path`` to the nearest sample of the demonstration."""
    return float(cKDTree(demo_pos).query(path)[0].mean())

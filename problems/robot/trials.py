"""Trials of a learned motion model driving the simulated arm (:class:`.arm.PandaSim`).

A trial starts the gripper at a pose (inverse kinematics, at rest), then at every simulator step
(240 Hz) reads the end-effector pose (x, q) and the current goal pose g(t), asks the model for the
twist (v, omega) = ``command(x, q, g)`` and sends the joint velocities of :mod:`.control`. A position
model (:func:`position_command`) gives v = f_g(x) with |v| <= v_max (``model.predictor(max_speed=v_max)``)
and the gripper holds the goal orientation (pointing down) by omega = K_ORIENT e_o; a pose model gives
both (``PoseCDSP.predictor(max_speed=v_max, max_angular_speed=w_max)``, :func:`pose_command`).
Disturbances: a push (a force on the end effector, and for pose trials a torque that twists it, for
:data:`PUSH_STEPS` steps) and a goal moved once by a few cm (for pose trials also turned by
:data:`GOAL_TURN_DEG`; the red ball and the blue bar along the goal's gripper axis move with it).
Measured per trial: the final distance and angle to the current goal, the time from which the gripper
stays within :data:`TOL` and :data:`ORI_TOL_DEG` of it, whether a joint came within 0.5 deg of a
limit, the peak joint speed (measured: a push can spin the wrist faster than the controller may; and
commanded), the largest displacement and turn the push caused, and for starts from a held-out
demonstration the path's mean distance to that demonstration. Success: within TOL and ORI_TOL_DEG of
the current goal pose at the end and no joint limit hit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from .arm import DOWN, RATE, wxyz, xyzw
from .control import K_ORIENT, rotation_error

TOL = 0.005                     # success radius (m)
ORI_TOL_DEG = 2.0               # success angle (deg)
MAX_SPEED = 0.25                # end-effector speed limit (m/s)
MAX_ANGULAR_SPEED = 1.0         # end-effector angular speed limit of pose models (rad/s)
PUSH_FORCE = 125.0              # N, horizontal, for PUSH_STEPS steps: a 6.25 N s shove
PUSH_TORQUE = 12.0              # N m about a random axis, pose trials: a 0.6 N m s twist
PUSH_STEPS = 12                 # 0.05 s at 240 Hz
GOAL_SHIFT = 0.04               # m
GOAL_TURN_DEG = 20.0            # pose trials: the goal orientation turned about a random axis
PUSH_WINDOW = (0.1, 0.3)        # push times: uniform in these fractions of the demos' duration
GOAL_WINDOW = (0.25, 0.45)      # goal-move times: the same
PATH_EVERY = 8                  # path samples kept: 30 Hz
DOWN_WXYZ = wxyz(DOWN)


@dataclass(frozen=True)
class TrialSpec:
    """One trial: task, start pose (x (3,), q (4,) w x y z), the held-out demo it starts from (index) or
    None (a random start), the push (time s, force N (3,), torque N m (3,) or None) or None, the goal
    move (time s, shift m (3,), turn: a world rotation vector (3,) or None) or None, duration s, and
    whether the model drives the orientation (``pose``)."""

    task: str
    start: np.ndarray
    demo: int | None
    push: tuple | None
    goal_move: tuple | None
    duration: float
    pose: bool = False


def trial_specs(task, demos, test_ids, rng, n_random, duration, *, pose=False) -> list[TrialSpec]:
    """The held-out demonstrations' starts cycle through (push and goal moved, neither, push, goal moved);
    ``n_random`` starts drawn uniformly in the box of the task's demos (grown by 5 cm, z >= 0.1 m) get
    both. Push and goal-move times: uniform in :data:`PUSH_WINDOW` / :data:`GOAL_WINDOW`. Pose trials
    (``pose``, ``demos`` with orientations): starts with the demo's orientation (random starts: a random
    sample's orientation of a random demo, turned by up to 45 deg), pushes that also twist, goal moves that
    also turn; position trials start pointing down."""
    X = np.vstack([d.pos for d in demos])
    lo, hi = X.min(axis=0) - 0.05, X.max(axis=0) + 0.05
    lo[2] = max(lo[2], 0.1)
    t_demo = float(np.mean([d.duration if hasattr(d, "duration") else d.t[-1] - d.t[0] for d in demos]))
    conditions = [(True, True), (False, False), (True, False), (False, True)]

    def unit(v):
        return v / np.linalg.norm(v)

    def spec(start, demo, push, move):
        angle, direction, axis, turn_axis = rng.uniform(0, 2 * np.pi), rng.normal(size=3), rng.normal(size=3), \
            rng.normal(size=3)
        return TrialSpec(task, start, demo,
                         (rng.uniform(*PUSH_WINDOW) * t_demo, PUSH_FORCE * np.array([np.cos(angle), np.sin(angle), 0.0]),
                          PUSH_TORQUE * unit(axis) if pose else None) if push else None,
                         (rng.uniform(*GOAL_WINDOW) * t_demo, GOAL_SHIFT * unit(direction),
                          np.deg2rad(GOAL_TURN_DEG) * unit(turn_axis) if pose else None) if move else None,
                         duration, pose)

    def random_start():
        x = rng.uniform(lo, hi)
        if not pose:
            return np.concatenate([x, DOWN_WXYZ])
        d = demos[int(rng.integers(len(demos)))]
        q = Rotation.from_rotvec(np.deg2rad(rng.uniform(0, 45)) * unit(rng.normal(size=3))) * \
            Rotation.from_quat(d.quat[int(rng.integers(len(d.t)))], scalar_first=True)
        return np.concatenate([x, q.as_quat(scalar_first=True)])

    starts = [np.concatenate([demos[i].pos[0], demos[i].quat[0] if pose else DOWN_WXYZ]) for i in test_ids]
    specs = [spec(s, i, *conditions[k % 4]) for k, (s, i) in enumerate(zip(starts, test_ids))]
    return specs + [spec(random_start(), None, True, True) for _ in range(n_random)]


def position_command(step):
    """``command(x, q, goal) -> (v, omega)`` of a position model's ``step(x, goal)``: v from the model, the
    goal orientation held by omega = K_ORIENT e_o (e_o the rotation vector from q to it)."""
    def command(x, q, goal):
        return step(x, goal[:3]), K_ORIENT * rotation_error(xyzw(q), xyzw(goal[3:]))
    return command


def pose_command(step):
    """``command(x, q, goal) -> (v, omega)`` of a pose model's ``step(x, q, goal)``."""
    return lambda x, q, goal: step(x, q, goal)


def angle_deg(qa, qb) -> float:
    """Geodesic angle (deg) between two unit quaternions (w x y z)."""
    return float(np.degrees(2.0 * np.arccos(min(1.0, abs(float(np.dot(qa, qb)))))))


def run_trial(sim, command, goal0, spec: TrialSpec, *, on_step=None) -> tuple[dict, dict]:
    """Drive the arm with ``command(x, q, goal) -> (v, omega)`` (speed-limited) from ``spec.start``
    towards the goal pose ``goal0`` (x, y, z, qw, qx, qy, qz); (measurements, path).

    ``on_step(k, t, sim, event)`` (optional) is called every step; ``event`` is "start", "push",
    "goal" (the first step of a disturbance) or None."""
    q0, ik_err = sim.solve_ik(spec.start[:3], xyzw(spec.start[3:]))
    goal = np.array(goal0, dtype=float)
    sim.reset(q0, goal if spec.pose else goal[:3])
    n = int(round(spec.duration * RATE))
    k_push = None if spec.push is None else int(round(spec.push[0] * RATE))
    k_goal = None if spec.goal_move is None else int(round(spec.goal_move[0] * RATE))
    ts, xs, gs, angles = np.arange(n + 1) / RATE, np.empty((n + 1, 3)), np.empty((n + 1, 7)), np.empty(n + 1)
    quats = np.empty((n + 1, 4))
    peak_qdot, peak_cmd, hit, push_disp, push_turn, x_push, q_push = 0.0, 0.0, False, 0.0, 0.0, None, None
    for k in range(n):
        x, q = sim.ee()
        q = wxyz(q)
        event = "start" if k == 0 else None
        if k == k_goal:
            _, shift, turn = spec.goal_move
            goal = np.concatenate([goal[:3] + shift, goal[3:] if turn is None else (
                Rotation.from_rotvec(turn) * Rotation.from_quat(goal[3:], scalar_first=True)).as_quat(scalar_first=True)])
            sim.move_marker(goal if spec.pose else goal[:3])
            event = "goal"
        if k_push is not None and k_push <= k < k_push + PUSH_STEPS:
            sim.push(spec.push[1], spec.push[2])
            if k == k_push:
                x_push, q_push, event = x, q, "push"
        if x_push is not None and k < k_push + 2 * int(RATE):
            push_disp = max(push_disp, float(np.linalg.norm(x - x_push)))
            push_turn = max(push_turn, angle_deg(q, q_push))
        xs[k], quats[k], gs[k], angles[k] = x, q, goal, angle_deg(q, goal[3:])
        if on_step is not None:
            on_step(k, ts[k], sim, event)
        v, w = command(x, q, goal)
        qdot_cmd = sim.command(np.concatenate([v, w]))
        peak_cmd = max(peak_cmd, float(np.abs(qdot_cmd).max()))
        sim.step()
        joints, qdot = sim.joints()
        peak_qdot = max(peak_qdot, float(np.abs(qdot).max()))
        hit = hit or sim.at_limit(joints)
    x, q = sim.ee()
    xs[n], quats[n], gs[n], angles[n] = x, wxyz(q), goal, angle_deg(wxyz(q), goal[3:])
    if on_step is not None:
        on_step(n, ts[n], sim, "end")
    err = np.linalg.norm(xs - gs[:, :3], axis=1)
    inside = (err < TOL) & (angles < ORI_TOL_DEG)
    row = {"method": None, "task": spec.task, "pose": spec.pose, "start": "demo" if spec.demo is not None else "random",
           "demo": spec.demo, "push": spec.push is not None, "goal_moved": spec.goal_move is not None,
           "success": bool(inside[-1] and not hit), "final_pos_err_m": float(err[-1]),
           "final_ori_err_deg": float(angles[-1]), "start_ori_err_deg": float(angles[0]),
           "time_to_goal_s": time_to_goal(ts, inside),
           "joint_limit_hit": hit, "peak_joint_speed_rad_s": peak_qdot, "peak_commanded_joint_speed_rad_s": peak_cmd,
           "push_time_s": None if spec.push is None else spec.push[0],
           "push_force_n": None if spec.push is None else spec.push[1].tolist(),
           "push_torque_nm": None if spec.push is None or spec.push[2] is None else spec.push[2].tolist(),
           "push_displacement_m": push_disp if spec.push is not None else None,
           "push_turn_deg": push_turn if spec.push is not None else None,
           "goal_move_time_s": None if spec.goal_move is None else spec.goal_move[0],
           "goal_shift_m": None if spec.goal_move is None else spec.goal_move[1].tolist(),
           "goal_turn_deg": None if spec.goal_move is None or spec.goal_move[2] is None else
           float(np.degrees(np.linalg.norm(spec.goal_move[2]))),
           "start_ik_error_m": ik_err, "duration_s": spec.duration}
    return row, {"t": ts[::PATH_EVERY], "x": xs[::PATH_EVERY], "quat": quats[::PATH_EVERY], "goal": gs[::PATH_EVERY]}


def time_to_goal(t, inside) -> float | None:
    """The first time from which ``inside`` holds to the end (None if it does not end there)."""
    outside = np.flatnonzero(~inside)
    if outside.size == 0:
        return float(t[0])
    return None if outside[-1] == len(inside) - 1 else float(t[outside[-1] + 1])


def path_deviation(path, demo_pos) -> float:
    """Mean distance (m) from each point of ``path`` to the nearest sample of the demonstration."""
    return float(cKDTree(demo_pos).query(path)[0].mean())

"""Pose reproduction metrics, the held-out protocol for pose models, and the detour tests.

Metrics:

* geodesic angle between unit quaternions (w x y z) p, q: theta = angle of (R_p^T R_q)
  (:meth:`scipy.spatial.transform.Rotation.magnitude`), in [0, pi]; q and -q give the same angle;
* orientation DTW: ``min_P sum_{(i, j) in P} theta(a_i, b_j)`` over monotone warping paths with
  steps (1,0), (0,1), (1,1) (the cumulative convention of :func:`~.metrics.dtwd`), in degrees;
* arrival: the first sample from which the trajectory stays within ``pos_tol`` of the goal
  position and ``ang_tol`` of the goal orientation (None if it never does).

Held-out protocol (:func:`evaluate_pose_set`), the steps of :mod:`.realdata` on both parts of the pose:

1. split: the first ceil(4N/7) demonstrations train, the rest test (:data:`~.realdata.TRAIN_FRACTION`);
2. training data: :func:`~sosdyn.lfd.data.pose_preprocess.preprocess_poses` (defaults chosen from the
   training demonstrations), then every 2nd sample; test data: the resting samples trimmed with the
   training noise levels (no smoothing, no alignment), every 2nd sample;
3. reproduction: explicit Euler (dt = 0.01 s) of the chart state from each test demo's 20th kept sample,
   stopped when every velocity component is below VEL_TOL_FRACTION x (the training positions' diagonal,
   resp. their largest angle from the goal) / the median training duration, for POS_TOL steps in a row
   (:func:`~sosdyn.lfd.rollout.euler_until_rest` on x / diag and r / angle), at most
   :func:`~.realdata.stop_rule`'s horizon; then **read at the test demo's own sampling period** (linear
   interpolation of x and r), so both curves of a DTW are sampled alike;
4. scores per test demo: position DTWD and orientation DTW to the whole kept test demo; the same of each
   recorded training demo (``train_pos`` / ``train_ori``, in recording order); copy = the
   smallest over the recorded training demos (picked with the test demo in hand, as no robot could);
   copy at the nearest start = the recorded training demo whose first sample is nearest the
   reproduction's start (:func:`nearest_start`: what a robot given only the start could replay); the
   orientation floor = the DTW of the test demo itself
   with its end turned onto the model's goal orientation (:func:`ended_at`: a perfect reproduction must
   end there, the test demos end elsewhere); the final distance to the goal position / diag and the
   final angle to the goal orientation; arrival (within 1 % of diag and 1 deg) over the demo's
   remaining duration; the certified excursion bound of the position block
   (:func:`~.realdata.excursion_bounds`).

Detour tests (:func:`detour_tests`): an orientation-only start (at the goal position, turned by an angle
about an axis) and a turn of the goal orientation after arrival; the largest displacement of the
position (0 for a cascade) and the angle and distance to the goal over time. :func:`far_starts`: every
test start turned 90-179 deg converges, with no refusal.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.limits import check_bytes
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.pose_preprocess import preprocess_poses, rest_range
from sosdyn.lfd.data.pose import (PoseDemonstration, PoseDemonstrations, align_orientations, angle_matrix, chart,
                                   from_chart, goal_orientation)
from sosdyn.lfd.rollout import euler_until_rest
from . import dsopt, realdata
from .metrics import DTWDistance, dtwd, warping_path_length

POS_TOL, ANG_TOL = 0.01, 1.0         # arrival / final-error targets: 1 % of the diagonal, 1 deg
DETOUR_ANGLES = (90.0, 170.0, 179.0)    # orientation-only starts (deg from the goal orientation)
GOAL_TURN_DEG = 30.0                 # the goal orientation's turn after arrival
FAR_ANGLES = (90.0, 150.0, 179.0)    # test starts turned this far from the goal orientation


def angles_deg(qa, qb) -> np.ndarray:
    """Geodesic angles (degrees) between the rows of qa and qb (same shape (T, 4), or one row)."""
    Ra = Rotation.from_quat(np.atleast_2d(qa), scalar_first=True)
    Rb = Rotation.from_quat(np.atleast_2d(qb), scalar_first=True)
    return np.rad2deg((Ra.inv() * Rb).magnitude())


def dtw_cost(C: np.ndarray) -> DTWDistance:
    """Cumulative DTW over the cost matrix C (N, M), by anti-diagonals (each a vector operation)."""
    N, M = C.shape
    check_bytes(8.0 * (N + 1) * (M + 1), f"DTW of {N} x {M} points (the cost matrix)", "subsample the curves")
    D = np.full((N + 1, M + 1), np.inf)
    D[0, 0] = 0.0
    for k in range(2, N + M + 1):
        i = np.arange(max(1, k - M), min(N, k - 1) + 1)
        j = k - i
        D[i, j] = C[i - 1, j - 1] + np.minimum(np.minimum(D[i - 1, j - 1], D[i - 1, j]), D[i, j - 1])
    length = warping_path_length(D)
    return DTWDistance(float(D[N, M]), float(D[N, M]) / length, (N, M), length)


def orientation_dtw(qa, qb) -> DTWDistance:
    """Orientation DTW (module docstring) between two quaternion curves (T, 4)."""
    return dtw_cost(angle_matrix(qa, qb))


def arrival_index(pos, quat, goal_pos, goal_quat, pos_tol: float, ang_tol_deg: float) -> int | None:
    """First index from which every sample is within pos_tol and ang_tol_deg of the goal pose."""
    inside = (np.linalg.norm(np.asarray(pos) - goal_pos, axis=1) <= pos_tol) & \
             (angles_deg(quat, goal_quat) <= ang_tol_deg)
    if not inside[-1]:
        return None
    outside = np.flatnonzero(~inside)
    return int(outside[-1] + 1) if outside.size else 0


# ---------------------------------------------------------------------- the held-out protocol
def _every_second(demos: PoseDemonstrations) -> PoseDemonstrations:
    s = dsopt.SAMPLE_STEP
    return PoseDemonstrations([PoseDemonstration(d.t[::s], d.pos[::s], d.quat[::s], d.source) for d in demos],
                              demos.name, demos.units)


def positions(demos) -> Demonstrations:
    """The positions of pose demonstrations as :class:`Demonstrations`."""
    return Demonstrations([Demonstration.from_positions(d.t, d.pos, d.source) for d in demos], demos.name, demos.units)


def prepare_poses(demos: PoseDemonstrations):
    """Protocol steps 1-2: (train for fitting, train as recorded, test, preprocessing report)."""
    k = math.ceil(realdata.TRAIN_FRACTION * len(demos))
    train, test = demos[:k], demos[k:]
    fitted, report = preprocess_poses(train)
    goal_quat = goal_orientation(train)

    def trim(ds):
        kept = []
        for d in ds:
            a, b = rest_range(d, goal_quat, report.position.noise, report.angle_noise)
            kept.append(PoseDemonstration(d.t[a:b + 1], d.pos[a:b + 1], d.quat[a:b + 1], d.source))
        return PoseDemonstrations(kept, demos.name, demos.units)
    return _every_second(fitted), _every_second(trim(train)), _every_second(trim(test)), report


def reproduce_poses(model, recorded: PoseDemonstrations, test: PoseDemonstrations) -> list[tuple[np.ndarray, np.ndarray]]:
    """Protocol step 3: per test demo, (t, chart states (x, r)) of the Euler reproduction from its 20th
    kept sample, read at the demo's sampling period."""
    vel_tol, max_steps = realdata.stop_rule(positions(recorded), positions(test))
    _, _, diag = realdata.box(positions(recorded))
    angle = max(float(np.linalg.norm(chart(d.quat, model.goal_quat_), axis=1).max()) for d in recorded) or 1.0
    unit = np.concatenate([np.full(3, diag), np.full(3, angle)])     # y = s / unit: one tolerance for both
    tol = vel_tol / diag                                             # = VEL_TOL_FRACTION / T_med
    starts = np.array([np.concatenate([d.pos[dsopt.START_INDEX], chart(d.quat[dsopt.START_INDEX], model.goal_quat_)[0]])
                       for d in test])
    paths = euler_until_rest(lambda Y: model.field(Y * unit, model.goal_pos_) / unit, starts / unit, dt=dsopt.DT,
                             max_steps=max_steps, vel_tol=tol, window=dsopt.WINDOW)
    out = []
    for d, path in zip(test, paths):
        h = float(np.median(np.diff(d.t)))
        t = np.arange(len(path)) * dsopt.DT
        grid = np.arange(0.0, t[-1] + 1e-9, h)
        out.append((grid, np.column_stack([np.interp(grid, t, path[:, i] * unit[i]) for i in range(6)])))
    return out


def nearest_start(recorded: PoseDemonstrations, pos, quat, diag: float) -> int:
    """The index of the demo of ``recorded`` whose first sample is nearest the pose (pos, quat):
    least |p_0 - pos| / diag + angle(q_0, quat) / 180 deg (a diagonal counts as much as a half turn)."""
    return int(np.argmin([np.linalg.norm(d.pos[0] - pos) / diag + angles_deg(d.quat[0], quat)[0] / 180.0
                          for d in recorded]))


def ended_at(demo: PoseDemonstration, goal_quat) -> PoseDemonstration:
    """``demo`` with its end orientation turned onto ``goal_quat`` (:func:`~sosdyn.lfd.data.pose.align_orientations`,
    no tolerance): what a model that reproduced it exactly would do, since it ends at its own goal."""
    return align_orientations(PoseDemonstrations([demo]), goal_quat, 180.0)[0][0]


def evaluate_pose_set(fit_fn, demos: PoseDemonstrations) -> dict:
    """The whole protocol (module docstring) on one set: ``fit_fn(train)`` returns a fitted PoseCDSP.
    Returns the per-test rows (``tests``), the mean ratios ``pos_ratio`` / ``ori_ratio`` (model over
    copy, means over the test demos), ``pos_start_ratio`` / ``ori_start_ratio`` (over the copy at the
    nearest start), the worst final errors and arrival, the largest certified
    excursion bound, ``ori_floor_ratio`` (the floor over copy), ``fit_s``, ``certified``, the preprocessing
    lines, the model and the reproductions."""
    train, recorded, test, report = prepare_poses(demos)
    t0 = time.perf_counter()
    model = fit_fn(train)
    fit_s = time.perf_counter() - t0
    reps = reproduce_poses(model, recorded, test)
    _, _, diag = realdata.box(positions(recorded))
    bounds = realdata.excursion_bounds(model.position_, positions(recorded), positions(test))
    rows = []
    for (t, S), d, bound in zip(reps, test, bounds):
        quat = from_chart(S[:, 3:], model.goal_quat_)
        near = nearest_start(recorded, d.pos[dsopt.START_INDEX], d.quat[dsopt.START_INDEX], diag)
        arrive = arrival_index(S[:, :3], quat, model.goal_pos_, model.goal_quat_, POS_TOL * diag, ANG_TOL)
        remaining = float(d.t[-1] - d.t[dsopt.START_INDEX])
        each_pos = [dtwd(tr.pos, d.pos).total for tr in recorded]
        each_ori = [orientation_dtw(tr.quat, d.quat).total for tr in recorded]
        rows.append({"pos_dtwd": dtwd(S[:, :3], d.pos).total, "ori_dtw": orientation_dtw(quat, d.quat).total,
                     "train_pos": each_pos, "train_ori": each_ori, "copy_pos": min(each_pos), "copy_ori": min(each_ori),
                     "start_copy_pos": each_pos[near], "start_copy_ori": each_ori[near],
                     "floor_ori": orientation_dtw(ended_at(d, model.goal_quat_).quat, d.quat).total,
                     "final_pos_frac": float(np.linalg.norm(S[-1, :3] - model.goal_pos_) / diag),
                     "final_ang_deg": float(np.rad2deg(np.linalg.norm(S[-1, 3:]))),
                     "arrival_ratio": None if arrive is None else float(t[arrive] / remaining),
                     "start_angle_deg": float(np.rad2deg(np.linalg.norm(S[0, 3:]))),
                     "max_angle_deg": float(np.rad2deg(np.linalg.norm(S[:, 3:], axis=1).max())),
                     "excursion_bound": bound, "n_points": len(t)})
    mean = {k: float(np.mean([r[k] for r in rows])) for k in ("pos_dtwd", "ori_dtw", "copy_pos", "copy_ori", "start_copy_pos",
                                                    "start_copy_ori", "floor_ori")}
    arrivals = [r["arrival_ratio"] for r in rows]
    return {"name": demos.name, "n_train": len(train), "n_test": len(test), "fit_s": fit_s,
            "certified": model.certified_, "preprocess": report.lines(demos.units), "diag": diag,
            "tests": rows, **mean, "pos_ratio": mean["pos_dtwd"] / mean["copy_pos"],
            "ori_ratio": mean["ori_dtw"] / mean["copy_ori"], "pos_start_ratio": mean["pos_dtwd"] / mean["start_copy_pos"],
            "ori_start_ratio": mean["ori_dtw"] / mean["start_copy_ori"], "ori_floor_ratio": mean["floor_ori"] / mean["copy_ori"],
            "final_pos_frac": max(r["final_pos_frac"] for r in rows), "final_ang_deg": max(r["final_ang_deg"] for r in rows),
            "arrival_ratio": None if None in arrivals else max(arrivals),
            "excursion_bound": None if None in bounds else max(bounds),
            "model": model, "train": train, "test": test, "reproductions": reps}


# ---------------------------------------------------------------------- detours and far starts
def turned(quat, angle_deg: float, axis) -> np.ndarray:
    """``quat`` (w x y z) turned by ``angle_deg`` about the world ``axis``."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return (Rotation.from_rotvec(np.deg2rad(angle_deg) * axis) * Rotation.from_quat(quat, scalar_first=True)).as_quat(
        scalar_first=True)


def _track(traj, start_pos) -> dict:
    """Time series of a pose trajectory: ``angle`` (deg) and ``distance`` (data units) to the goal pose in
    effect, and the position's ``displacement`` from ``start_pos``."""
    return {"t": traj.t, "angle": angles_deg(traj.quat, traj.goal_history[:, 3:]),
            "distance": np.linalg.norm(traj.pos - traj.goal_history[:, :3], axis=1),
            "displacement": np.linalg.norm(traj.pos - start_pos, axis=1)}


def detour_tests(model, duration: float, axes, diag: float) -> dict:
    """The orientation-only starts (DETOUR_ANGLES about each of ``axes``, at the goal position) and a
    goal turn (GOAL_TURN_DEG about each axis, from the goal pose, at duration / 4): per case the largest
    displacement of the position / diag, the final angle and the time series (:func:`_track`)."""
    g, q = model.goal_pos_, model.goal_quat_
    cases = []
    for axis in axes:
        for angle in DETOUR_ANGLES:
            traj = model.rollout(np.concatenate([g, turned(q, angle, axis)]), duration)
            cases.append({"kind": "orientation-only start", "angle_deg": angle, "axis": list(map(float, axis)),
                          **_track(traj, g)})
        new_goal = np.concatenate([g, turned(q, GOAL_TURN_DEG, axis)])
        traj = model.rollout(np.concatenate([g, q]), duration, goal_changes=[(duration / 4, new_goal)])
        cases.append({"kind": "goal turn", "angle_deg": GOAL_TURN_DEG, "axis": list(map(float, axis)),
                      **_track(traj, g)})
    for c in cases:
        c["max_displacement_frac"] = float(c["displacement"].max() / diag)
        c["final_angle_deg"] = float(c["angle"][-1])
    return {"cases": cases, "max_displacement_frac": max(c["max_displacement_frac"] for c in cases)}


def far_starts(model, test: PoseDemonstrations, duration: float, axes, diag: float) -> dict:
    """Every test demo's start position with the goal orientation turned FAR_ANGLES about each of
    ``axes``: rollouts of ``duration`` s; the worst final distance / diag and angle, and the largest
    angle along the way (never above the start's: the angle is monotone)."""
    worst_pos, worst_ang, rise = 0.0, 0.0, 0.0
    for d in test:
        for axis in axes:
            for angle in FAR_ANGLES:
                traj = model.rollout(np.concatenate([d.pos[0], turned(model.goal_quat_, angle, axis)]), duration)
                a = angles_deg(traj.quat, model.goal_quat_)
                worst_pos = max(worst_pos, float(np.linalg.norm(traj.pos[-1] - model.goal_pos_) / diag))
                worst_ang, rise = max(worst_ang, float(a[-1])), max(rise, float(a.max() - a[0]))
    return {"n": len(test) * len(axes) * len(FAR_ANGLES), "final_pos_frac": worst_pos, "final_ang_deg": worst_ang,
            "max_angle_rise_deg": rise}


__all__ = ["angle_matrix", "angles_deg", "arrival_index", "detour_tests", "dtw_cost", "evaluate_pose_set",
           "far_starts", "orientation_dtw", "prepare_poses", "reproduce_poses", "turned"]

"""The models that drive the arm, each as ``fit(name, train) -> (command, fit record)`` with
``command(x, q, goal) -> (v, omega)`` (:mod:`.trials`).

Position methods (positions in m; the gripper holds the goal orientation, pointing down): ``CDSP``
(``sd.CDSP()``, its ``predictor(max_speed=...)``) and its baseline ``GMR`` (no stability guarantee), the
field translated to the goal and speed-limited alike. Pose methods (positions and orientations): ``PoseCDSP``
(``sd.PoseCDSP()``, its ``predictor(max_speed=..., max_angular_speed=...)``: v and the angular velocity
omega = R J_r(r) rdot) and its baseline ``GMR pose``: a GMR of the positions and a GMR of the rotation
vector r = log(R_g^T R) (the same goal orientation and aligned ends), omega = R J_r(r) rdot, scaled by the
same single factor. Every method goes through the same controller.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

import sosdyn as sd
from sosdyn.evaluation.baselines import GMR
from sosdyn.lfd.data.pose import align_orientations, chart, goal_orientation, split_demonstrations
from sosdyn.lfd.runtime.pose import body_velocity, pose_speed_factor
from sosdyn.lfd.runtime.states import limit_speed

from ..settings import SEED
from .trials import MAX_ANGULAR_SPEED, MAX_SPEED, pose_command, position_command

POSITION_METHODS = ("CDSP", "GMR")
POSE_METHODS = ("PoseCDSP", "GMR pose")


def gmr_pose_step(pos_model, rot_model, max_speed, max_angular_speed):
    """``step(x, q, goal) -> (v, omega)`` of the GMR pose baseline (module docstring)."""
    origin = np.zeros((1, 3))

    def step(x, q, goal):
        r = chart(q, goal[3:])
        v, rdot = pos_model.field(x[None], goal[:3])[0], rot_model.field(r, origin)[0]
        lam = float(pose_speed_factor(r, np.concatenate([v, rdot])[None], max_speed, max_angular_speed)[0, 0])
        w = Rotation.from_quat(q, scalar_first=True).apply(body_velocity(r, rdot)[0])
        return lam * v, lam * w
    return step


def fit(name: str, train):
    """(command, fit record) of method ``name`` on ``train`` (Demonstrations for the position methods,
    PoseDemonstrations for the pose methods)."""
    t0 = time.perf_counter()
    if name == "CDSP":
        model = sd.CDSP(random_state=SEED).fit(train)
        command = position_command(model.predictor(max_speed=MAX_SPEED))
        record = {"certified": bool(model.certified_), "warp": model.warp_ is not None}
    elif name == "GMR":
        model = GMR(random_state=SEED).fit(train)
        command = position_command(lambda x, goal: limit_speed(model.field(x[None], goal), MAX_SPEED)[0])
        record = {}
    elif name == "PoseCDSP":
        model = sd.PoseCDSP(random_state=SEED).fit(train)
        command = pose_command(model.predictor(max_speed=MAX_SPEED, max_angular_speed=MAX_ANGULAR_SPEED))
        record = {"certified": model.certified_, "warp": model.position_.warp_ is not None,
                  "still": {k: v is not None for k, v in model.still_.items()}}
    else:
        goal_quat = goal_orientation(train)
        pos, rot = split_demonstrations(align_orientations(train, goal_quat)[0], goal_quat)
        command = gmr_pose_step(GMR(random_state=SEED).fit(pos), GMR(random_state=SEED).fit(rot), MAX_SPEED,
                                MAX_ANGULAR_SPEED)
        record = {}
    return command, dict(record, fit_time_s=time.perf_counter() - t0)

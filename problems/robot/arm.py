"""The simulated arm: a Franka Panda in pybullet (headless, ``p.DIRECT``), stepped at 240 Hz.

:class:`PandaSim` holds the simulator's state: it reads the end-effector pose and Jacobian, sends
joint velocities (``VELOCITY_CONTROL`` with the Panda's torque limits) for an end-effector twist,
pushes and twists the end effector (``applyExternalForce`` / ``applyExternalTorque``), moves the goal
marker (a red ball, and a blue bar along the goal orientation's gripper axis z), solves inverse
kinematics for a start and renders camera frames with the CPU TinyRenderer. The control law is
:mod:`.control`. Quaternions are pybullet's (x, y, z, w) here; :func:`wxyz` / :func:`xyzw` convert
to and from sosdyn's (w, x, y, z).
"""
from __future__ import annotations

import numpy as np
import pybullet as p
import pybullet_data

from .control import joint_velocities, rotation_error

URDF = "franka_panda/panda.urdf"
EE_LINK = 11                     # panda_grasptarget: between the fingertips
ARM = tuple(range(7))            # panda_joint1..7; 9 and 10 are the fingers
FINGERS = (9, 10)
HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
#: Gripper pointing down (x, y, z, w): a half turn about the world x axis.
DOWN = np.array([1.0, 0.0, 0.0, 0.0])
RATE = 240.0
#: Panda velocity limits (rad/s; datasheet) -- the URDF's own are the same.
QDOT_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
#: A joint this close to its limit (rad) counts as hitting it.
HIT = np.deg2rad(0.5)
AXIS_BAR = 0.06                  # m: length of the goal marker's bar along the goal gripper axis


def wxyz(q) -> np.ndarray:
    """pybullet's (x, y, z, w) as sosdyn's (w, x, y, z)."""
    return np.array([q[3], q[0], q[1], q[2]], dtype=float)


def xyzw(q) -> np.ndarray:
    """sosdyn's (w, x, y, z) as pybullet's (x, y, z, w)."""
    return np.array([q[1], q[2], q[3], q[0]], dtype=float)


class PandaSim:
    """One headless pybullet world with the Panda on a floor and a goal marker (a red sphere)."""

    def __init__(self, width=480, height=360):
        self.client = p.connect(p.DIRECT)
        c = self.client
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=c)
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(1.0 / RATE, physicsClientId=c)
        p.loadURDF("plane.urdf", physicsClientId=c)
        self.robot = p.loadURDF(URDF, useFixedBase=True, physicsClientId=c)
        info = [p.getJointInfo(self.robot, j, physicsClientId=c) for j in ARM]
        self.lo = np.array([i[8] for i in info])
        self.hi = np.array([i[9] for i in info])
        self.torque = np.array([i[10] for i in info])
        shape = p.createVisualShape(p.GEOM_SPHERE, radius=0.02, rgbaColor=[0.85, 0.1, 0.1, 1],
                                    physicsClientId=c)
        self.marker = p.createMultiBody(baseMass=0, baseVisualShapeIndex=shape, physicsClientId=c)
        bar = p.createVisualShape(p.GEOM_BOX, halfExtents=[0.006, 0.006, AXIS_BAR / 2], rgbaColor=[0.1, 0.3, 0.85, 1],
                                  visualFramePosition=[0, 0, AXIS_BAR / 2], physicsClientId=c)
        self.bar = p.createMultiBody(baseMass=0, baseVisualShapeIndex=bar, physicsClientId=c)
        self.size = (width, height)
        self.reset(HOME)

    def close(self):
        p.disconnect(self.client)

    # ------------------------------------------------------------------ state
    def reset(self, q, goal=None):
        """Joints to q (at rest), fingers closed, goal marker at ``goal`` (position, or pose x, y, z + w x y z)."""
        for j, qj in zip(ARM, q):
            p.resetJointState(self.robot, j, float(qj), 0.0, physicsClientId=self.client)
        for j in FINGERS:
            p.resetJointState(self.robot, j, 0.0, physicsClientId=self.client)
        p.setJointMotorControlArray(self.robot, FINGERS, p.POSITION_CONTROL, targetPositions=[0.0, 0.0],
                                    physicsClientId=self.client)
        if goal is not None:
            self.move_marker(goal)

    def joints(self) -> tuple[np.ndarray, np.ndarray]:
        """(q, qdot) of the seven arm joints."""
        s = p.getJointStates(self.robot, ARM, physicsClientId=self.client)
        return np.array([x[0] for x in s]), np.array([x[1] for x in s])

    def ee(self) -> tuple[np.ndarray, np.ndarray]:
        """End-effector position (3,) and orientation (x, y, z, w) in the world frame."""
        s = p.getLinkState(self.robot, EE_LINK, computeForwardKinematics=True, physicsClientId=self.client)
        return np.array(s[4]), np.array(s[5])

    def jacobian(self, q) -> np.ndarray:
        """[J_v; J_w] (6, 7) of the end-effector point at joint angles q."""
        full = list(map(float, q)) + [0.0, 0.0]
        jv, jw = p.calculateJacobian(self.robot, EE_LINK, [0.0, 0.0, 0.0], full, [0.0] * 9, [0.0] * 9,
                                     physicsClientId=self.client)
        return np.vstack([np.array(jv)[:, :7], np.array(jw)[:, :7]])

    def at_limit(self, q) -> bool:
        return bool(np.any((q - self.lo < HIT) | (self.hi - q < HIT)))

    # ------------------------------------------------------------------ acting
    def command(self, twist) -> np.ndarray:
        """Send the joint velocities that realise the end-effector twist (v, omega) (6,) (world frame);
        returns them (:func:`.control.joint_velocities`)."""
        q, _ = self.joints()
        qdot = joint_velocities(self.jacobian(q), np.asarray(twist, dtype=float), q, self.lo, self.hi, QDOT_MAX)
        p.setJointMotorControlArray(self.robot, ARM, p.VELOCITY_CONTROL, targetVelocities=qdot.tolist(),
                                    forces=self.torque.tolist(), physicsClientId=self.client)
        return qdot

    def push(self, force, torque=None):
        """Apply ``force`` (N) at the end effector, and ``torque`` (N m) to it, world frame, during the next step."""
        pos, _ = self.ee()
        p.applyExternalForce(self.robot, EE_LINK, list(map(float, force)), pos.tolist(), p.WORLD_FRAME,
                             physicsClientId=self.client)
        if torque is not None:
            p.applyExternalTorque(self.robot, EE_LINK, list(map(float, torque)), p.WORLD_FRAME,
                                  physicsClientId=self.client)

    def step(self):
        p.stepSimulation(physicsClientId=self.client)

    def move_marker(self, goal):
        """The ball to the goal position, the bar along the goal orientation's z axis (pose goals only)."""
        goal = np.asarray(goal, dtype=float)
        p.resetBasePositionAndOrientation(self.marker, goal[:3].tolist(), [0, 0, 0, 1], physicsClientId=self.client)
        where = (goal[:3].tolist(), xyzw(goal[3:]).tolist()) if goal.size == 7 else ([0, 0, -1.0], [0, 0, 0, 1])
        p.resetBasePositionAndOrientation(self.bar, *where, physicsClientId=self.client)

    # ------------------------------------------------------------------ kinematics
    def solve_ik(self, pos, orientation=DOWN, iters=600, tol=1e-4) -> tuple[np.ndarray, float]:
        """Joint angles placing the end effector at ``pos`` with ``orientation`` (x, y, z, w), by the
        same damped least squares as the controller (kinematic steps from HOME); (q, position error)."""
        self.reset(HOME)
        q = HOME.copy()
        for _ in range(iters):
            x, quat = self.ee()
            e = np.concatenate([np.asarray(pos) - x, rotation_error(quat, orientation)])
            if np.linalg.norm(e[:3]) < tol and np.linalg.norm(e[3:]) < 1e-3:
                break
            q = np.clip(q + joint_velocities(self.jacobian(q), e, q, self.lo, self.hi, QDOT_MAX / 5),
                        self.lo, self.hi)
            self.reset(q)
        x, _ = self.ee()
        return q, float(np.linalg.norm(np.asarray(pos) - x))

    # ------------------------------------------------------------------ camera
    def render(self, size=None, target=(0.4, 0.0, 0.35), distance=1.35, yaw=105.0, pitch=-18.0) -> np.ndarray:
        """An RGB frame (h, w, 3) of ``size`` (w, h; default the world's) from the CPU TinyRenderer."""
        w, h = self.size = size or self.size
        view = p.computeViewMatrixFromYawPitchRoll(target, distance, yaw, pitch, 0, 2)
        proj = p.computeProjectionMatrixFOV(45, w / h, 0.05, 5.0)
        img = p.getCameraImage(w, h, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=self.client)
        self.camera = (np.array(view).reshape(4, 4).T, np.array(proj).reshape(4, 4).T)
        return np.reshape(img[2], (h, w, 4))[:, :, :3].astype(np.uint8)

    def to_pixels(self, X) -> np.ndarray:
        """Pixel coordinates (m, 2) of world points X (m, 3) in the last rendered frame."""
        view, proj = self.camera
        Xh = np.hstack([np.atleast_2d(X), np.ones((len(np.atleast_2d(X)), 1))])
        clip = Xh @ (proj @ view).T
        ndc = clip[:, :2] / clip[:, 3:]
        w, h = self.size
        return np.column_stack([(ndc[:, 0] + 1) * w / 2, (1 - ndc[:, 1]) * h / 2])

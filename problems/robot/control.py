"""Task-space velocity control of a redundant arm, as plain array maths (no simulator here).

The learned model gives the desired end-effector velocity v (3,); the gripper keeps a fixed
orientation R* by the angular velocity w = k_o e_o, e_o the rotation vector of R* R^T. The joint
velocities solve the 6-D task t = [v; w] by damped least squares on the arm's Jacobian J (6, n):

    qdot = J^# t + (I - J^+ J) qdot_0,      J^# = J^T (J J^T + lambda^2 I)^-1 = V diag(s/(s^2+lambda^2)) U^T,

(J = U diag(s) V^T; J^+ J = V_r V_r^T is the exact projector onto the row space, so the
self-motion leaves the end effector alone even where the damping shifts the task part)

and the self-motion qdot_0 = -k_l grad H(q) pushes the joints away from their limits,
H(q) = 1/2 sum_i ((q_i - qbar_i) / (q_hi,i - q_lo,i))^2 (mid-range criterion). Two safety nets
follow: a joint within ``guard`` rad of a limit may not move further towards it (its velocity set
to 0), and the whole vector is scaled down by one factor so that every |qdot_i| <= qdot_max,i (the
direction of motion unchanged).
"""
from __future__ import annotations

import numpy as np

#: Damping lambda of the least squares (small against the Jacobian's singular values ~0.1-1).
DAMPING = 0.02
#: Gain of the orientation hold (1/s) and of the joint-limit self-motion.
K_ORIENT = 4.0
K_LIMITS = 2.0
#: A joint this close to a limit (rad) may only move away from it.
GUARD = np.deg2rad(2.0)


def rotation_error(q_cur, q_des) -> np.ndarray:
    """Rotation vector (3,) turning the orientation ``q_cur`` into ``q_des`` (quaternions x, y, z, w),
    in the world frame: e = theta a for q_des q_cur^-1 = (a sin(theta/2), cos(theta/2))."""
    x1, y1, z1, w1 = q_des
    x2, y2, z2, w2 = -q_cur[0], -q_cur[1], -q_cur[2], q_cur[3]       # conjugate = inverse
    w = w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2
    v = np.array([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                  w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                  w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])
    if w < 0:                                                        # the shorter way round
        w, v = -w, -v
    s = np.linalg.norm(v)
    return np.zeros(3) if s < 1e-12 else v * (2.0 * np.arctan2(s, w) / s)


def limit_gradient(q, lo, hi) -> np.ndarray:
    """grad H of the mid-range criterion H = 1/2 sum ((q - (lo+hi)/2) / (hi - lo))^2."""
    return (q - 0.5 * (lo + hi)) / (hi - lo) ** 2


def joint_velocities(J, twist, q, lo, hi, qdot_max, *, damping=DAMPING, k_limits=K_LIMITS,
                     guard=GUARD) -> np.ndarray:
    """qdot (n,) for the task velocity ``twist`` (6,) at the joint angles q (module docstring)."""
    U, sv, Vt = np.linalg.svd(J, full_matrices=True)
    r = len(sv)
    task = Vt[:r].T @ ((sv / (sv ** 2 + damping ** 2)) * (U.T @ twist))
    free = Vt[r:]                                    # rows spanning the null space of J
    qdot = task - k_limits * (free.T @ (free @ limit_gradient(q, lo, hi)))
    blocked = ((q - lo < guard) & (qdot < 0)) | ((hi - q < guard) & (qdot > 0))
    qdot = np.where(blocked, 0.0, qdot)
    return qdot * min(1.0, float(np.min(qdot_max / np.maximum(np.abs(qdot), 1e-12))))


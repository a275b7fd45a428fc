"""The tracking field of a second-order model: what the demonstrations do near them, and a pull
back to them off them (the nominal acceleration that :mod:`.tank` certifies).

Scaled units as :mod:`.core` (e = ((x - g)/s, v T/s), a' = a T^2/s). The field tracks the
training samples (e_i, a_i), i = 1..N (positions, velocities and accelerations of the demos, plus a
critically damped landing from each demo's last state at the goal, :func:`landing_samples`):

    a*(e) = (1 - phi(e)) sum_i w_i(e) [a_i + w^2 x_i + 2 w v_i] - w^2 e_x - 2 w e_v,
    w_i(e) = exp(-|D (e - e_i)|^2 / 2) / sum_j exp(-|D (e - e_j)|^2 / 2),   D = diag(1/h_x, .., 1/h_v, ..),
    phi(e) = exp(-|e|^2 / (2 r^2)),   r = GOAL_RADIUS,

away from the goal (phi ~ 0) a Nadaraya-Watson average of the demos' accelerations, each corrected by
a critically damped pull (rate w) to its own sample. The kernel weighs position AND velocity, so at a
crossing (one x, two v) the two branches are different samples and the field follows the branch the
state is on. Far from the data the weight goes to the nearest sample and a* pulls towards it. Near
the goal (|e| ~ r) a* becomes the critically damped landing -w^2 e_x - 2 w e_v: the slow last samples
of the demos would otherwise pull the state towards themselves, behind the goal, and hold it at a few
per cent of the scale from it (measured: rollouts creeping at 1 % of the diagonal on the crossing
set, 4-9 % on LASA Spoon and Worm). a* alone certifies nothing; :mod:`.tank` filters it.
"""
from __future__ import annotations

import numpy as np

from ...data.demonstrations import Demonstrations
from .core import Scaled, demo_derivatives

LANDING_STEPS = 60          # steps of dt' of each landing sample path (critically damped at rate w)
CHUNK = 128                 # states per block of the kernel sums (memory ~ CHUNK x N x 2n)
#: r: within ~r of (g, 0) (scaled units) the field is the critically damped landing. Chosen on training
#: rollouts (from the training demos' own starts): r = 0.05 left LASA Spoon and Worm creeping at 4-9 % of
#: the diagonal from the goal, 0.1 arrives (0.2-0.4 %), 0.2 cuts the inner loop of crossing/at (training
#: DTWD 3742 -> 18518).
GOAL_RADIUS = 0.1


def landing_samples(demos: Demonstrations, scaled: Scaled, omega: float,
                    steps: int = LANDING_STEPS) -> tuple[np.ndarray, np.ndarray]:
    """(E, Ea) in scaled units: from each demo's last (x, v) (the window's Savitzky-Golay fit), the
    critically damped landing a = -w^2 e_x - 2 w e_v integrated by semi-implicit Euler with the
    data's step for ``steps`` steps, and the goal at rest (0, 0). A demo whose recording was trimmed
    while it still moved says nothing about stopping; these samples do."""
    parts, _ = demo_derivatives(demos, scaled.window)
    n = demos.dim
    E, A = [np.zeros(2 * n)], [np.zeros(n)]
    for pos, vel, _ in parts:
        e = np.concatenate([(pos[-1] - scaled.goal) / scaled.length, vel[-1] * scaled.time / scaled.length])
        for _ in range(steps):
            a = -omega ** 2 * e[:n] - 2.0 * omega * e[n:]
            E.append(e.copy())
            A.append(a)
            e[n:] += scaled.dt * a
            e[:n] += scaled.dt * e[n:]
    return np.array(E), np.array(A)


def tracking_set(demos: Demonstrations, scaled: Scaled, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """The samples the field tracks: the scaled demo samples and their landings, (N, 2n) and (N, n)."""
    E, A = landing_samples(demos, scaled, omega)
    return np.vstack([scaled.E, E]), np.vstack([scaled.Ea, A])


def kernel_widths(n: int, position: float, velocity: float) -> np.ndarray:
    """(1/h) per coordinate of e: n position widths, then n velocity widths."""
    return np.concatenate([np.full(n, 1.0 / position), np.full(n, 1.0 / velocity)])


def tracking_accelerations(E: np.ndarray, S: np.ndarray, Sa: np.ndarray, inv_widths: np.ndarray,
                           omega: float) -> np.ndarray:
    """a*(e) (module docstring) at the rows of E (m, 2n) for the samples S (N, 2n), Sa (N, n); the
    softmax is taken after subtracting each row's smallest exponent, so no weight underflows to a
    0/0; the exponents are sums of squared differences (no cancellation far from the data). Blocks of
    CHUNK rows keep the (rows x N x 2n) differences small."""
    n = Sa.shape[1]
    target = tracking_targets(S, Sa, omega)
    out = np.empty((len(E), n))
    for lo in range(0, len(E), CHUNK):
        e = E[lo:lo + CHUNK]
        d2 = 0.5 * np.square((e[:, None, :] - S[None, :, :]) * inv_widths).sum(axis=2)
        W = np.exp(-(d2 - d2.min(axis=1, keepdims=True)))
        fade = 1.0 - np.exp(-np.einsum("ij,ij->i", e, e) / (2.0 * GOAL_RADIUS ** 2))
        out[lo:lo + CHUNK] = fade[:, None] * ((W @ target) / W.sum(axis=1, keepdims=True)) \
            - omega ** 2 * e[:, :n] - 2.0 * omega * e[:, n:]
    return out


def tracking_targets(S: np.ndarray, Sa: np.ndarray, omega: float) -> np.ndarray:
    """a_i + w^2 x_i + 2 w v_i per sample (N, n): a*(e) = sum_i w_i(e) target_i - w^2 e_x - 2 w e_v."""
    n = Sa.shape[1]
    return Sa + omega ** 2 * S[:, :n] + 2.0 * omega * S[:, n:]


__all__ = ["CHUNK", "GOAL_RADIUS", "LANDING_STEPS", "kernel_widths", "landing_samples", "tracking_accelerations", "tracking_set",
           "tracking_targets"]

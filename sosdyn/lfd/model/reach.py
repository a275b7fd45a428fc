"""Where a certified trajectory can go: a box that contains it for all time (docs/theory.md,
"How far a trajectory can go").

With a constant metric M (``metric_degree`` 0) the certificate J_k^T M + M J_k <= -gamma M
(everywhere, every k) makes V(u) = u^T M u non-increasing along every trajectory of the certified
system u' = sum_k h_k f_k(u) (u = z, or u = phi(z) with a warp; z = (x - goal) / scale), so the
trajectory from u0 stays in the ellipsoid E = {u^T M u <= V0}, V0 = u0^T M u0, whose extent
along coordinate i is |u_i| <= r_i = sqrt(V0 (M^-1)_ii). A warp moves a point by
z - phi(z) = -sum_j t_j v_j with t_j = rho_j(.) - rho_j(0) in [-rho_j(0), 1 - rho_j(0)], so
z_i lies in [w_i + d_lo_i, w_i + d_hi_i] (w = B(z), the bumps' image) with d_lo_i / d_hi_i the
sums over the maps of the smaller / larger of rho_j(0) v_ji and -(1 - rho_j(0)) v_ji. Without a
twist w = u, |w_i| <= r_i; with one (:mod:`~sosdyn.lfd.fit.twist`), w = R(-alpha) u rotates u in
the plane P = [p; q] by an unknown angle, so w_i = e_i^T (I - P^T P) u + (rotated in-plane part)
and |w_i| <= r_i = sqrt(V0 (Q M^-1 Q)_ii) + |P e_i| sqrt(V0 lambda_max(P M^-1 P^T)), Q = I - P^T P.
Hence, for all t,

    x(t) in [goal + scale (-r + d_lo), goal + scale (r + d_hi)]          (:func:`reach_box`),

and the excursion of the trajectory outside any box is at most the box's
(:func:`sosdyn.lfd.rollout.quality.box_excursion`). The bound holds for the exact flow of a
certified model; a state-dependent metric gives no bound here (None).
"""
from __future__ import annotations

import numpy as np

from ..fit.contraction import constant_index, eval_metric
from ..fit.composite import apply as warp_apply, maps_of, twist_of
from ..fit.warp import bumps_at


def metric_matrix(model) -> np.ndarray | None:
    """The certified metric M of a fitted CDSP when it is constant (metric_degree 0 or
    identity), else None."""
    used = np.abs(model.W_).max(axis=(0, 1)) > 0
    k = constant_index(model.metric_exps_)
    return None if used.sum() != 1 or not used[k] else \
        eval_metric(model.W_, model.metric_exps_, np.zeros((1, model.dim_)))[0]


def warp_shift(centers, vectors, sigmas) -> tuple[np.ndarray, np.ndarray]:
    """(d_lo, d_hi), each (n,): z - phi(z) lies in the box [d_lo, d_hi] for every z (goal 0)."""
    V = np.asarray(vectors, dtype=float)
    rho0 = bumps_at(np.zeros(V.shape[1]), centers, sigmas)[:, None]          # rho_j(0), (m, 1)
    a, b = rho0 * V, -(1.0 - rho0) * V
    return np.minimum(a, b).sum(axis=0), np.maximum(a, b).sum(axis=0)


def reach_box(model, X0) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi), each (k, n): a box in data units containing the whole trajectory of ``model``'s
    certified flow from each start X0 (k, n) (module docstring); None when the metric is not
    constant."""
    M = metric_matrix(model)
    if M is None:
        return None
    Z = (np.atleast_2d(np.asarray(X0, dtype=float)) - model.goal_) / model.scale_
    n = Z.shape[1]
    if model.warp_ is None:
        U, d_lo, d_hi = Z, np.zeros(n), np.zeros(n)
    else:
        U = warp_apply(Z, model.warp_)
        d_lo, d_hi = warp_shift(*maps_of(model.warp_))
    level = np.maximum(np.einsum("ki,ij,kj->k", U, M, U), 0.0)
    Minv, twist = np.linalg.inv(M), twist_of(model.warp_)
    if twist is None:
        r = np.sqrt(level[:, None] * np.diag(Minv)[None])
    else:
        P = twist[0]
        Q = np.eye(n) - P.T @ P
        reach = np.sqrt(np.maximum(np.diag(Q @ Minv @ Q), 0.0)) + \
            np.linalg.norm(P, axis=0) * np.sqrt(np.linalg.eigvalsh(P @ Minv @ P.T).max())
        r = np.sqrt(level)[:, None] * reach[None]
    return model.goal_ + model.scale_ * (d_lo - r), model.goal_ + model.scale_ * (d_hi + r)

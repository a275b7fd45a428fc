"""The second-order fit (:func:`fit_second_order`) and its joint step: fields C and metric M
together, by an inner convex approximation of the bilinear LMI (as the first-order :class:`~.steps.ICAStep`).

With F = companion(C), dF = F - F0 = [[0, 0], [dC]], dM = M - M0 the exact identity

    F^T M + M F = F0^T M + M F0 + F^T M0 + M0 F - F0^T M0 - M0 F0 + dF^T dM + dM dF

and Young's inequality dF^T dM + dM dF <= a dC^T dC + dM^2 / a give the sufficient condition
(a Schur complement) for L_k = F_k^T M + M F_k + 2 gamma M <= -delta I:

    [[-(lin_k(C, M) + 2 gamma M) - delta I,  dC_k^T,   dM ],
     [ dC_k,                                 I_n / a,  0  ],        PSD,
     [ dM,                                   0,        a I]]

affine in (C, M) and satisfied at (C0, M0) whenever L_k(C0, M0) <= -delta I: every iterate stays
certified and the least-squares cost cannot increase (the current point is feasible). M keeps
M >= eps I and trace M = 2n. A proximal term rho (|C - C0|^2 + |M - M0|^2) makes the step unique.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sosdyn.poly import PolyMatrix
from sosdyn.sos import SOSProgram, svec_to_matrix
from ..gmm import PositionMixture
from ..learner import cap_note
from .core import (METRIC_EPS, Scaled, companion, decision_companion, energy_metric_step, field_step, lmi,
                           metric_step,
                           nominal_fields, tracking_samples, training_deviation)
from ..steps import LeastSquaresData, solve_with_fallback
from ..steps.common import proximal


def _entries(block) -> np.ndarray:
    """A PolyMatrix's or a number matrix's entries as an object array (for np.block)."""
    return block.entries if isinstance(block, PolyMatrix) else np.asarray(block, dtype=float).astype(object)


def block_matrix(rows) -> PolyMatrix:
    """The PolyMatrix ``[[rows[0][0], rows[0][1], ...], ...]`` of PolyMatrix / number blocks."""
    return PolyMatrix(np.block([[_entries(b) for b in row] for row in rows]))


def lmi_margin(C, M, gamma) -> float:
    """min_k lambda_min(-L_k) for numbers C, M: the margin the current iterate has."""
    return float(min(np.linalg.eigvalsh(-lmi(F, M, gamma))[0] for F in companion(C)))


def ica_step(data: LeastSquaresData, C0, M0, gamma, margin, alpha=1.0, prox=1e-4, eps=METRIC_EPS,
             solver="CLARABEL"):
    """One joint step from the certified (C0, M0) (``margin`` <= its LMI margin). Returns (C, M, cost)."""
    K, n, m = data.shape
    prog = SOSProgram("second-order ICA step")
    ids = prog.new_ids(K * n * m, name="fields")
    M = prog.new_psd(m, name="M")
    prog.add_sos_matrix(M - PolyMatrix.identity(m) * eps, name="metric positive")
    prog.add_eq(sum(M[a, a] for a in range(m)), float(m), name="trace M = 2n")
    dM = M - M0
    zn, zm = np.zeros((n, m)), np.zeros((m, n))
    for k, own in enumerate(ids.reshape(K, n * m)):
        F, F0 = decision_companion(own, n), companion(C0[k:k + 1])[0]
        lin = F0.T @ M + M @ F0 + F.T @ M0 + M0 @ F - (F0.T @ M0 + M0 @ F0) + M * (2.0 * gamma)
        dC = F[n:, :] - C0[k]
        prog.add_sos_matrix(block_matrix([[-lin - PolyMatrix.identity(m) * margin, dC.T, dM],
                                          [dC, np.eye(n) / alpha, zn],
                                          [dM, zm, np.eye(m) * alpha]]), name=f"ica[{k}]")
    sv = np.array([M0[a, b] * (1.0 if a == b else np.sqrt(2.0)) for b in range(m) for a in range(b + 1)])
    order = np.argsort(M.ids)
    prog.minimize(data.form(ids) + proximal(ids, C0.ravel(), prox) + proximal(M.ids[order], sv[order], prox))
    sol = solve_with_fallback(prog, solver, affine_psd=True)
    C = sol.values_of(ids).reshape(K, n, m)
    return C, svec_to_matrix(sol.values_of(M.ids), m), data.cost(C)


@dataclass
class SecondOrderFit:
    """The result of :func:`fit_second_order`: fields C (K, n, 2n), metric M, margin, the gating
    mixture on e, the scales, one history row per iterate and the row of the iterate chosen."""

    scaled: Scaled
    mixture: PositionMixture
    C: np.ndarray
    M: np.ndarray
    margin: float
    history: list = field(default_factory=list)
    chosen: int = 0


METHODS = ("ica", "alternating", "energy")
ENERGY_ROWS = 500               # demo samples in the energy metric step
ALPHA_MIN = 1e-3                # Young's weight a stays in [1e-3, 1e3]
COST_FLOOR = 1e-12              # the stopping test's relative tolerance never divides by less


def converged(old: float, new: float, tol: float) -> bool:
    """The fit loop's stopping test: the cost fell by at most ``tol`` relative to the new cost."""
    return old - new <= tol * max(new, COST_FLOOR)


def capped(rows: list[dict], max_iter: int, tol: float) -> str | None:
    """:func:`~sosdyn.lfd.fit.learner.cap_note` when the history rows of a fit (a "start" row, then one
    per iteration) show all ``max_iter`` iterations run and the last still changing the cost by more
    than ``tol`` (:func:`converged`); None otherwise (fewer iterations, or none: the tracking field)."""
    if len(rows) < 2 or len(rows) - 1 < max_iter:
        return None
    old, new = rows[-2]["cost"], rows[-1]["cost"]
    return None if converged(old, new, tol) else cap_note(max_iter, (old - new) / max(new, COST_FLOOR), tol)


def fit_second_order(scaled: Scaled, mixture: PositionMixture, gamma: float, margin: float, max_iter: int,
                     tol: float, prox: float = 1e-2, method: str = "ica", solver="CLARABEL",
                     progress=None, tracking=None) -> SecondOrderFit:
    """Fit C and M in scaled units (``gamma`` in 1/s of the data, gamma' = gamma T).

    Start: M of the critically damped nominal fields (:func:`~.core.metric_step`), then the
    field step under it. Each iteration is, for ``method`` "ica", a joint step (:func:`ica_step`,
    Young weight a = 1) followed by a field step under its M (a = |dM| / |dC| of the previous joint step, the
    weight that makes Young's bound tight for a step like it); for "alternating", a metric step
    (max margin, proximal) then a field step. Every step keeps the current fields feasible, so
    the cost never increases; stop when it falls by less than ``tol`` (relative) in an iteration.
    Every iterate is certified; the one returned is the one whose rollouts from the training
    demos' first states deviate least from them (:func:`~.core.training_deviation`): the
    acceleration cost is a poor proxy for a twice-integrated path near a crossing.
    """
    g = gamma * scaled.time
    n = scaled.Ea.shape[1]
    K = mixture.n_components
    E, Ea = tracking_samples(scaled, *tracking) if tracking else (scaled.E, scaled.Ea)
    data = LeastSquaresData(mixture.responsibilities(E), E, Ea)
    history = []

    def log(row):
        row = dict(row, iteration=len(history))
        history.append(row)
        if progress is not None:
            progress(row)

    live = np.flatnonzero(np.linalg.norm(scaled.E, axis=1) > 1e-3)
    pick = live[::max(1, len(live) // ENERGY_ROWS)]
    demo = (scaled.E[pick], np.hstack([scaled.E[pick, n:], scaled.Ea[pick]]))
    M, t = metric_step(nominal_fields(n, K, max(1.0, 2.0 * g)), g, solver=solver)
    C, cost = field_step(data, M, g, min(margin, t), solver)
    best = (training_deviation(C, mixture, scaled), C, M, 0)
    log({"step": "start", "cost": cost, "margin": min(margin, t), "deviation": best[0]})
    alpha = 1.0
    for _ in range(max_iter):
        if method == "ica":
            C1, M1, _ = ica_step(data, C, M, g, min(margin, lmi_margin(C, M, g)), alpha, prox * 1e-2, solver=solver)
            t = lmi_margin(C1, M1, g)
            dC, dM = np.linalg.norm(C1 - C), np.linalg.norm(M1 - M)
            if dC > 0 and dM > 0:       # Young's bound is tightest for a = |dM| / |dC|
                alpha = float(np.clip(dM / dC, ALPHA_MIN, 1.0 / ALPHA_MIN))
        elif method == "energy":
            M1 = energy_metric_step(C, g, *demo, min(margin, lmi_margin(C, M, g)), M, prox, solver=solver)
            t = lmi_margin(C, M1, g)
        else:
            M1, t = metric_step(C, g, M, prox, solver=solver)
        if t <= 0:              # round-off broke the inner approximation's guarantee: stop here
            break
        C_new, new = field_step(data, M1, g, min(margin, t), solver)
        if new > cost:          # round-off: the current fields stay (they are feasible under M1)
            break
        C, M, old, cost = C_new, M1, cost, new
        dev = training_deviation(C, mixture, scaled)
        log({"step": method, "cost": new, "margin": t, "cond_M": float(np.linalg.cond(M1)), "deviation": dev})
        if dev < best[0]:
            best = (dev, C, M, len(history) - 1)
        if converged(old, cost, tol):
            break
    dev, C, M, chosen = best
    return SecondOrderFit(scaled, mixture, C, M, lmi_margin(C, M, g), history, chosen)

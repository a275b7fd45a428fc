"""Second-order CDSP: the maths on arrays (data, gating, the two convex steps, the alternation).

State z = (x, v) in R^{2n}, goal g, equilibrium z* = (g, 0). In scaled units (length s, time T,
:func:`scaled_samples`) e = (e_x, e_v) = ((x - g)/s, v T/s) and

    de_x/dt' = e_v,   de_v/dt' = sum_k h_k(e) C_k e,   i.e.  de/dt' = sum_k h_k(e) F_k e,
    F_k = [[0, I], [A_k, B_k]],  C_k = [A_k, B_k]  (n x 2n),  t' = t / T.

Certificate (docs/theory.md, "Second order"): one constant M > 0 (2n x 2n) with

    L_k = F_k^T M + M F_k + 2 gamma' M  <=  -margin I   for every k   (gamma' = gamma T),

so V(e) = e^T M e obeys dV/dt' <= -2 gamma' V for ANY weights h in the simplex: the gating may
depend on x and v (which is what lets two branches cross at one x with different v).

Fitting alternates two convex programs through :class:`~sosdyn.sos.SOSProgram` (constant PSD
constraints, as the first-order steps in :mod:`sosdyn.lfd.fit.steps`):

* field step (M fixed): least squares of the accelerations (:class:`sosdyn.lfd.fit.steps.LeastSquaresData`
  with features e) subject to -L_k - delta I >= 0, linear in C_k;
* metric step (C fixed): maximise t with -L_k - t I >= 0, M - eps I >= 0, trace M = 2n (the
  scale of M is free), plus a proximal term rho |M - M0|^2.

The field step's margin is min(margin, t) with t the metric step's margin, so the current fields
stay feasible and the training cost cannot increase. The first metric is the one of the
critically damped nominal system A = -w^2 I, B = -2 w I (w = max(1, 2 gamma')).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sosdyn.errors import InputError, SolverError
from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos import SOSProgram, svec_to_matrix
from sosdyn.sos.gram import matrix_to_svec
from ...data.demonstrations import Demonstrations, sample_step
from ...data.preprocess import resample_uniform, savgol_derivatives, smoothing_window
from ...rollout import semi_implicit_euler
from ..gmm import MIN_SAMPLES_PER_COMPONENT, PositionMixture, fit_joint_gmm
from ..learner import subsample
from ..steps import LeastSquaresData, solve_with_fallback
from ..steps.common import proximal

DERIV_WINDOW = 9                # Savitzky-Golay window for smooth data (as estimate_velocity)
METRIC_EPS = 1e-3               # M >= eps I (trace M = 2n)
T_MAX = 10.0                    # the metric step's margin bound
ROLLOUT_STEPS = 1000            # training_deviation's Euler steps at most


@dataclass(frozen=True)
class Scaled:
    """Samples in scaled units: E (N, 2n) = (e_x, e_v), Ea (N, n) = a T^2 / s; goal g, s, T; per
    demo its first state (``starts`` (m, 2n)), its positions e_x (``paths``) and the step dt / T."""

    goal: np.ndarray
    length: float
    time: float
    E: np.ndarray
    Ea: np.ndarray
    window: int
    starts: np.ndarray
    paths: list
    dt: float


def demo_derivatives(demos: Demonstrations, window: int | None = None):
    """Per demo (pos, vel, acc) from one cubic Savitzky-Golay fit
    (:func:`~sosdyn.lfd.data.preprocess.savgol_derivatives`)
    after resampling to uniform steps; ``window`` None: the preprocess "auto" window, or
    DERIV_WINDOW when the data are smooth. Returns (list of (pos, vel, acc), window)."""
    uniform = [resample_uniform(d) for d in demos]
    if window is None:
        window = smoothing_window(uniform) or DERIV_WINDOW
    return [tuple(savgol_derivatives(d.t, d.pos, window, order=2)) for d in uniform], window


def scaled_samples(demos: Demonstrations, n_components: int, max_samples, window=None) -> Scaled:
    """The stacked samples in scaled units: s = max |x_c - g_c| (1 if 0), T = s / v_rms (v_rms the
    root-mean-square speed, so e_v has RMS 1); subsampled to ``max_samples``. InputError if fewer
    than MIN_SAMPLES_PER_COMPONENT samples per Gaussian remain or the demos do not move."""
    parts, window = demo_derivatives(demos, window)
    X, V, A = (np.vstack([p[i] for p in parts]) for i in range(3))
    X, VA, _ = subsample(X, np.hstack([V, A]), max_samples)
    n = X.shape[1]
    V, A = VA[:, :n], VA[:, n:]
    if X.shape[0] < MIN_SAMPLES_PER_COMPONENT * n_components:
        raise InputError(f"{X.shape[0]} samples are too few for {n_components} Gaussians; use fewer "
                         "components, more demonstrations or a larger max_samples.")
    goal = np.asarray(demos.goal, dtype=float)
    s = float(np.abs(X - goal).max()) or 1.0
    v_rms = float(np.sqrt((V ** 2).sum(axis=1).mean()))
    if not v_rms > 0:
        raise InputError("the demonstrations do not move (zero velocity everywhere); nothing to learn.")
    T = s / v_rms
    starts = np.array([np.concatenate([(p[0][0] - goal) / s, p[1][0] * T / s]) for p in parts])
    return Scaled(goal, s, T, np.hstack([(X - goal) / s, V * T / s]), A * T * T / s, window, starts,
                  [(p[0] - goal) / s for p in parts], sample_step(demos) / T)


def tracking_samples(scaled: Scaled, copies: int, sigma: float, omega: float, seed: int):
    """(E, Ea) of the samples and ``copies`` perturbed copies of each: e + d, d ~ N(0, sigma^2 I)
    (scaled units), labelled a - w^2 d_x - 2 w d_v (a critically damped pull back to the demo at
    rate w). They teach the fields to return to a demonstration they were pushed off, which the
    accelerations along the demos alone do not say; ``copies`` 0: the samples alone."""
    if copies == 0:
        return scaled.E, scaled.Ea
    n = scaled.Ea.shape[1]
    d = np.random.default_rng(seed).normal(0.0, sigma, size=(copies,) + scaled.E.shape)
    E = np.vstack([scaled.E] + [scaled.E + di for di in d])
    Ea = np.vstack([scaled.Ea] + [scaled.Ea - omega ** 2 * di[:, :n] - 2 * omega * di[:, n:] for di in d])
    return E, Ea


def fit_gating(E: np.ndarray, n_components: int, seed: int) -> PositionMixture:
    """A full-covariance GMM on the scaled states e = (e_x, e_v) (EM, :func:`~sosdyn.lfd.fit.gmm.fit_joint_gmm`):
    h_k(e) are its responsibilities."""
    n = E.shape[1] // 2
    gmm, _ = fit_joint_gmm(E[:, :n], E[:, n:], n_components, seed)
    return PositionMixture(gmm.weights_.copy(), gmm.means_.copy(), gmm.covariances_.copy())


def companion(C: np.ndarray) -> np.ndarray:
    """F_k = [[0, I], [A_k, B_k]] (K, 2n, 2n) from C (K, n, 2n) = [A_k, B_k]."""
    K, n, _ = C.shape
    F = np.zeros((K, 2 * n, 2 * n))
    F[:, :n, n:] = np.eye(n)
    F[:, n:, :] = C
    return F


def lmi(F, M, gamma):
    """L = F^T M + M F + 2 gamma M (numbers, or PolyMatrix when F or M is one)."""
    return F.T @ M + M @ F + 2.0 * gamma * M


def accelerations(C, H, E):
    """sum_k h_k C_k e at the rows of E (N, 2n), H (N, K) the weights: (N, n)."""
    return np.einsum("tk,kij,tj->ti", H, C, E)


def acceleration_at(X, V, goal, length, time, mixture: PositionMixture, C) -> np.ndarray:
    """Accelerations (N, n) in data units at positions X and velocities V (N, n) for the goal
    ``goal``: a = (s / T^2) sum_k h_k(e) C_k e, e = ((x - g)/s, v T/s). The gating sees x - g, so a
    goal change translates the motion."""
    E = np.hstack([(X - goal) / length, V * (time / length)])
    return accelerations(C, mixture.responsibilities(E), E) * (length / time ** 2)


def training_deviation(C, mixture: PositionMixture, scaled: Scaled) -> float:
    """Mean over the training demos of the mean distance (scaled units) between each demo and the
    model's rollout from the demo's first (x, v) at the same times: semi-implicit Euler with the
    data's step times ceil(samples / ROLLOUT_STEPS) (:func:`~sosdyn.lfd.rollout.semi_implicit_euler`,
    all demos at once; explicit Euler would add energy to an oscillating motion and favour
    over-damped fields). Time-aligned, so a rollout that wanders over the demo's region in another
    order does not score well (a nearest-point distance would). A diverging rollout scores inf."""
    n = C.shape[1]

    def acc(X, V):
        E = np.hstack([X, V])
        return accelerations(C, mixture.responsibilities(E), E)
    longest = max(len(p) for p in scaled.paths)
    stride = -(-longest // ROLLOUT_STEPS)
    try:
        paths = semi_implicit_euler(acc, scaled.starts[:, :n], scaled.starts[:, n:], dt=scaled.dt * stride,
                                    steps=(longest - 1) // stride)
    except (SolverError, InputError):
        return float("inf")
    return float(np.mean([np.linalg.norm(paths[:, i][:len(p[::stride])] - p[::stride], axis=1).mean()
                          for i, p in enumerate(scaled.paths)]))


def decision_companion(ids: np.ndarray, n: int) -> PolyMatrix:
    """[[0, I], [C]] with C (n x 2n) the decision variables ``ids`` (row-major), as a PolyMatrix."""
    entries = np.empty((2 * n, 2 * n), dtype=object)
    for i in range(n):
        for j in range(2 * n):
            entries[i, j] = Polynomial.constant(1.0 if j == n + i else 0.0)
            entries[n + i, j] = Polynomial.affine([ids[i * 2 * n + j]], [1.0])
    return PolyMatrix(entries)


def field_step(data: LeastSquaresData, M, gamma, margin, solver="CLARABEL"):
    """M fixed: C (K, n, 2n) minimising the data term with -L_k - margin I PSD for every k.
    Returns (C, cost)."""
    K, n, m = data.shape
    prog = SOSProgram("second-order field step")
    ids = prog.new_ids(K * n * m, name="fields")
    I = PolyMatrix.identity(m)
    for k, own in enumerate(ids.reshape(K, n * m)):
        prog.add_sos_matrix(-lmi(decision_companion(own, n), M, gamma) - I * margin, name=f"contraction[{k}]")
    prog.minimize(data.form(ids))
    sol = solve_with_fallback(prog, solver, affine_psd=True)
    C = sol.values_of(ids).reshape(K, n, m)
    return C, data.cost(C)


def metric_step(C, gamma, M0=None, prox=0.0, eps=METRIC_EPS, solver="CLARABEL"):
    """C fixed: M (trace 2n, M >= eps I) maximising the margin t, -L_k - t I PSD, t <= T_MAX;
    with ``prox`` > 0 maximise t - prox |svec(M) - svec(M0)|^2 (a unique maximiser). Returns (M, t)."""
    F = companion(C)
    m = F.shape[1]
    prog = SOSProgram("second-order metric step")
    M = prog.new_psd(m, name="M")
    t = prog.new_var(name="margin")
    I = PolyMatrix.identity(m)
    prog.add_sos_matrix(M - I * eps, name="metric positive")
    prog.add_eq(sum(M[a, a] for a in range(m)), float(m), name="trace M = 2n")
    prog.add_ge(T_MAX - t, 0.0, name="margin bound")
    for k in range(F.shape[0]):
        prog.add_sos_matrix(-lmi(F[k], M, gamma) - I * t, name=f"contraction[{k}]")
    if prox > 0 and M0 is not None:
        sv = np.array([M0[a, b] * (1.0 if a == b else np.sqrt(2.0)) for b in range(m) for a in range(b + 1)])
        order = np.argsort(M.ids)
        prog.minimize(proximal(M.ids[order], sv[order], prox) + (-t))
    else:
        prog.maximize(t)
    sol = solve_with_fallback(prog, solver, affine_psd=True)
    return svec_to_matrix(sol.values_of(M.ids), m), float(sol.values_of(t.ids)[0])   # the solver's margin: a target


def energy_metric_step(C, gamma, E, Edot, margin, M0, prox=0.0, eps=METRIC_EPS, solver="CLARABEL"):
    """C fixed: the metric along which the demonstrations themselves best obey the certified
    decrease. With S_t = (e_t de_t^T + de_t e_t^T + 2 gamma e_t e_t^T) / |e_t|^2 (rows of E, Edot),
    minimise mean_t max(0, tr(M S_t)) (+ prox |M - M0|^2) subject to -L_k - margin I PSD for the
    current fields (so they stay feasible), M >= eps I, trace M = 2n. Returns M."""
    F = companion(C)
    m = F.shape[1]
    prog = SOSProgram("second-order energy metric step")
    M = prog.new_psd(m, name="M")
    I = PolyMatrix.identity(m)
    prog.add_sos_matrix(M - I * eps, name="metric positive")
    prog.add_eq(sum(M[a, a] for a in range(m)), float(m), name="trace M = 2n")
    for k in range(F.shape[0]):
        prog.add_sos_matrix(-lmi(F[k], M, gamma) - I * margin, name=f"contraction[{k}]")
    S = np.einsum("ti,tj->tij", E, Edot)
    S = S + S.transpose(0, 2, 1) + 2 * gamma * np.einsum("ti,tj->tij", E, E)
    S /= np.einsum("ti,ti->t", E, E)[:, None, None]
    sv = np.array([matrix_to_svec(St) for St in S])               # tr(M S_t) = svec(M) . svec(S_t)
    slack = prog.new_ids(len(S), name="violations")
    for t, (row, sid) in enumerate(zip(sv, slack)):
        prog.add_ge(Polynomial.affine([sid], [1.0]), 0.0, name=f"slack[{t}]")
        prog.add_ge(Polynomial.affine(np.concatenate([[sid], M.ids]), np.concatenate([[1.0], -row])), 0.0,
                    name=f"violation[{t}]")
    mean = Polynomial.affine(slack, np.full(len(slack), 1.0 / len(slack)))
    sv0 = matrix_to_svec(M0)
    order = np.argsort(M.ids)
    prog.minimize(proximal(M.ids[order], sv0[order], prox) + mean)
    sol = solve_with_fallback(prog, solver, affine_psd=True)
    return svec_to_matrix(sol.values_of(M.ids), m)


def nominal_fields(n: int, K: int, omega: float) -> np.ndarray:
    """C of the critically damped system A = -w^2 I, B = -2 w I, for every component."""
    return np.tile(np.hstack([-omega ** 2 * np.eye(n), -2 * omega * np.eye(n)]), (K, 1, 1))

"""CLF-DM baseline (Khansari-Zadeh & Billard 2014, "Learning control Lyapunov function to
ensure stability of dynamical system-based robot reaching motions", RAS 62(6)).

Own implementation, in goal-shifted coordinates x = position − goal:

1. Nominal field f(x): GMR (:class:`~sosdyn.evaluation.baselines.gmr.GMR`), no guarantee.
2. Energy: the weighted sum of asymmetric quadratic functions (WSAQF)

       V(x) = xᵀP₀x + Σ_{l=1}^{L} β_l(x) (xᵀP_l(x − μ_l))²,
       β_l(x) = 1 if xᵀP_l(x − μ_l) ≥ 0 else 0,   P_l ≻ 0,

   learned from the data alone by minimising the paper's objective

       J = (1/m) Σ_i (1+w)/2 sign(ψ_i) ψ_i² + (1−w)/2 ψ_i²,   ψ_i = ∇V(x_i)ᵀẋ_i / (‖∇V(x_i)‖‖ẋ_i‖),

   i.e. ψ² for each demonstrated velocity that climbs V and −wψ² (a small reward) for
   each that descends it.
3. Online correction (control Lyapunov function): with ρ(x) = ρ₀(1 − exp(−κ₀‖x‖²))‖∇V(x)‖,

       ẋ = f(x) + u(x),   u = −(∇Vᵀf + ρ) ∇V / ‖∇V‖²   only where ∇Vᵀf + ρ > 0,

   which gives V̇ ≤ −ρ < 0 away from the goal.  ρ is written as in the authors' released
   CLFDM code (``DS_stabilizer.m``): the paper's ρ(‖x‖) = ρ₀(1 − e^{−κ₀‖x‖}) measured in
   V per second becomes a minimum speed ρ₀(1 − e^{−κ₀‖x‖²}) along −∇V/‖∇V‖, which does not
   depend on the arbitrary scale of V and vanishes smoothly at the goal.

A goal change shifts the coordinates: x = position − new goal.
"""

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from sosdyn.errors import InputError
from sosdyn.evaluation.baselines.base import AutonomousModel, check_int, check_points
from sosdyn.lfd.rollout import as_positive
from sosdyn.evaluation.baselines.gmr import GMR


_LOG_BOUND = 6.0   # |log C_ii|, |C_ij| ≤ 6 in unit-scaled coordinates


@dataclass(frozen=True)
class WSAQF:
    """V(x) = xᵀP₀x + Σ_l β_l(x)(xᵀP_l(x − μ_l))² in goal-shifted coordinates.

    ``P`` (L+1, n, n) holds P₀, P₁, …, P_L (symmetric positive definite); ``mu`` (L, n).
    """

    P: np.ndarray
    mu: np.ndarray

    def _asymmetric(self, X):
        """s_l = xᵀP_l(x − μ_l) (m, L), active β_l s_l (m, L) and P_l(2x − μ_l) (m, L, n)."""
        Px = np.einsum("lij,mj->mli", self.P[1:], X)
        s = np.einsum("mi,mli->ml", X, Px) - np.einsum("mli,li->ml", Px, self.mu)
        Pa = 2.0 * Px - np.einsum("lij,lj->li", self.P[1:], self.mu)[None]
        return s, np.where(s >= 0.0, s, 0.0), Pa

    def value(self, X):
        """V at the rows of ``X`` (m, n), shape (m,)."""
        _, bs, _ = self._asymmetric(X)
        return np.einsum("mi,ij,mj->m", X, self.P[0], X) + np.sum(bs * bs, axis=1)

    def gradient(self, X):
        """∇V = 2P₀x + Σ_l 2β_l s_l P_l(2x − μ_l) at the rows of ``X``, shape (m, n)."""
        _, bs, Pa = self._asymmetric(X)
        return 2.0 * X @ self.P[0] + 2.0 * np.einsum("ml,mli->mi", bs, Pa)


def _unpack(theta, n, L):
    """θ → (Cholesky factors C (L+1, n, n) with log-diagonals, μ (L, n)); P_l = C_l C_lᵀ."""
    rows, cols = np.tril_indices(n)
    m = rows.size
    C = np.zeros((L + 1, n, n))
    C[:, rows, cols] = theta[: (L + 1) * m].reshape(L + 1, m)
    diag = np.arange(n)
    C[:, diag, diag] = np.exp(C[:, diag, diag])
    return C, theta[(L + 1) * m:].reshape(L, n)


def wsaqf_objective(theta, Z, V, L, w):
    """J(θ) of the module docstring and its exact gradient (data: unit directions V)."""
    n = Z.shape[1]
    C, mu = _unpack(theta, n, L)
    P = C @ C.transpose(0, 2, 1)
    energy = WSAQF(P, mu)
    s, bs, Pa = energy._asymmetric(Z)
    g = 2.0 * Z @ P[0] + 2.0 * np.einsum("ml,mli->mi", bs, Pa)
    gnorm = np.maximum(np.linalg.norm(g, axis=1), 1e-12)
    psi = np.sum(g * V, axis=1) / gnorm
    weight = np.where(psi > 0.0, 1.0, -w)
    J = np.mean(weight * psi ** 2)
    # dJ/dg per point, then chain through g = 2P₀z + Σ 2β_l s_l P_l a_l, a_l = 2z − μ_l.
    G = (2.0 * weight * psi / Z.shape[0])[:, None] * (V - psi[:, None] * g / gnorm[:, None]) \
        / gnorm[:, None]
    dP = np.empty_like(P)
    dP[0] = 2.0 * G.T @ Z
    q = np.einsum("mi,mli->ml", G, Pa)                       # Gᵀ P_l a_l
    active = (s >= 0.0).astype(float)
    A = 2.0 * Z[:, None, :] - mu[None]                       # a_l (m, L, n)
    dP[1:] = 2.0 * (np.einsum("ml,mi,mlj->lij", bs, G, A)
                    + np.einsum("ml,mi,mlj->lij", active * q, Z, Z[:, None, :] - mu[None]))
    PZ = np.einsum("lij,mj->mli", P[1:], Z)
    PG = np.einsum("lij,mj->mli", P[1:], G)
    dmu = -2.0 * np.einsum("ml,mli->li", active * q, PZ) - 2.0 * np.einsum("ml,mli->li", bs, PG)
    dC = (dP + dP.transpose(0, 2, 1)) @ C
    rows, cols = np.tril_indices(n)
    dC_vec = dC[:, rows, cols]
    dC_vec[:, rows == cols] *= C[:, rows[rows == cols], cols[rows == cols]]
    return J, np.concatenate([dC_vec.ravel(), dmu.ravel()])


def fit_wsaqf(X, Xdot, n_asymmetric, w=1e-4, n_init=5, random_state=0, max_iter=1000):
    """Learn a :class:`WSAQF` from goal-shifted positions ``X`` and velocities ``Xdot``.

    Minimises J (module docstring) with L-BFGS-B over Cholesky factors (log-diagonal, so
    every P_l ≻ 0) and the centres μ_l, in coordinates scaled by max‖x‖.  Each of the
    ``n_init`` starts has P_l = I and μ_l at distinct training points drawn with
    ``random_state``; the start reaching the lowest J wins.  Rows with x = 0 or ẋ = 0 carry
    no direction and are ignored.
    """
    X = np.asarray(X, dtype=float)
    Xdot = np.asarray(Xdot, dtype=float)
    L = check_int(n_asymmetric, "n_asymmetric", minimum=0)
    speed = np.linalg.norm(Xdot, axis=1)
    keep = (speed > 0) & (np.linalg.norm(X, axis=1) > 0)
    if keep.sum() <= L + 1:
        raise InputError("too few moving data points away from the goal to learn a WSAQF; "
                         "check that the demonstrations move and end at the goal.")
    scale = np.max(np.linalg.norm(X[keep], axis=1))
    Z, V = X[keep] / scale, Xdot[keep] / speed[keep, None]
    n = X.shape[1]
    n_chol = (L + 1) * (n * (n + 1) // 2)
    # Bounded factors keep the scale-invariant J from drifting to overflow.
    bounds = [(-_LOG_BOUND, _LOG_BOUND)] * n_chol + [(-2.0, 2.0)] * (L * n)
    rng = np.random.default_rng(random_state)
    best = None
    for _ in range(check_int(n_init, "n_init")):
        theta0 = np.concatenate([   # C_l = I, μ_l at training points
            np.zeros(n_chol), Z[rng.choice(Z.shape[0], size=L, replace=False)].ravel()])
        result = minimize(wsaqf_objective, theta0, args=(Z, V, L, w), jac=True, method="L-BFGS-B",
                          bounds=bounds, options={"maxiter": max_iter})
        if best is None or result.fun < best.fun:
            best = result
    C, mu = _unpack(best.x, n, L)
    # Back to unscaled coordinates x = scale·z: P_l → P_l / scale², μ_l → scale·μ_l.
    return WSAQF(C @ C.transpose(0, 2, 1) / scale ** 2, mu * scale)


class CLFDM(AutonomousModel):
    """CLF-DM: GMR nominal field + learned WSAQF energy + online correction (module doc).

    Parameters
    ----------
    n_components : int
        K, Gaussians of the nominal GMR.
    n_asymmetric : int
        L, asymmetric quadratic terms of the WSAQF (L = 0 gives a quadratic energy).
    w : float
        Small weight rewarding velocities that descend V (paper: 1e-4).
    rho0, kappa0 : float or None
        Gains of ρ. ``None`` picks them relative to the data, matching the authors' LASA
        settings (ρ₀ = 1 mm/s, κ₀ = 0.1 mm⁻²) to within ~25%:
        ρ₀ = 0.05 · mean demonstrated speed and κ₀ = (15 / max‖x_i − goal‖)².
    n_init : int
        Starts of the WSAQF optimisation (the lowest J is kept).
    energy_subsample : int
        The WSAQF is learned from every ``energy_subsample``-th sample (plus each demo's
        last); J is a mean over near-duplicate neighbours, so 5 loses little and is ~7x faster.
    random_state : int
        Seed of EM and of the WSAQF starts.
    max_iter : int
        L-BFGS iterations for the WSAQF.

    Learned attributes: ``gmr_``, ``energy_`` (:class:`WSAQF`), ``rho0_``, ``kappa0_``,
    ``goal_``, ``dim_``, ``dt_``.
    """

    name = "CLF-DM"

    def __init__(self, n_components=6, n_asymmetric=6, w=1e-4, rho0=None, kappa0=None,
                 n_init=5, energy_subsample=5, random_state=0, max_iter=1000):
        self.n_components = n_components
        self.n_asymmetric = n_asymmetric
        self.w = w
        self.rho0 = rho0
        self.kappa0 = kappa0
        self.n_init = n_init
        self.energy_subsample = energy_subsample
        self.random_state = random_state
        self.max_iter = max_iter

    def fit(self, demos):
        w = as_positive(self.w, "w")
        if w >= 1:
            raise InputError(f"w must be a small positive weight below 1 (paper: 1e-4), got {w}.")
        demos = self._learn_frame(demos)
        self.gmr_ = GMR(n_components=self.n_components, random_state=self.random_state).fit(demos)
        X, Xdot = demos.subsample(check_int(self.energy_subsample, "energy_subsample")).stacked()
        X = X - self.goal_
        self.energy_ = fit_wsaqf(X, Xdot, self.n_asymmetric, w=w, n_init=self.n_init,
                                 random_state=self.random_state,
                                 max_iter=check_int(self.max_iter, "max_iter"))
        speed = np.linalg.norm(Xdot, axis=1).mean()
        reach = np.max(np.linalg.norm(X, axis=1))
        self.rho0_ = 0.05 * speed if self.rho0 is None else as_positive(self.rho0, "rho0")
        self.kappa0_ = (15.0 / reach) ** 2 if self.kappa0 is None \
            else as_positive(self.kappa0, "kappa0")
        return self

    def energy(self, X, goal=None):
        """V at the rows of ``X`` (m, n) for ``goal`` (default: the training goal)."""
        self._check_fitted()
        goal = self.goal_ if goal is None else goal
        return self.energy_.value(check_points(X, self.dim_) - goal)

    def nominal_field(self, X, goal):
        """The uncorrected GMR field f, translated to ``goal``."""
        return self.gmr_.field(X, goal)

    def field(self, X, goal):
        """f(x) + u(x): the nominal field corrected so that V̇ ≤ −ρ (module docstring)."""
        Xdot = self.nominal_field(X, goal)
        x = X - goal
        grad = self.energy_.gradient(x)
        gnorm2 = np.sum(grad * grad, axis=1)
        rho = self.rho0_ * (1.0 - np.exp(-self.kappa0_ * np.sum(x * x, axis=1))) \
            * np.sqrt(gnorm2)
        excess = np.sum(grad * Xdot, axis=1) + rho
        active = (excess > 0.0) & (gnorm2 > 0.0)
        Xdot[active] -= (excess[active] / gnorm2[active])[:, None] * grad[active]
        return Xdot

"""Refinement of the GMM's position marginal (the paper's theta_G in eq. 18).

The certificate does not depend on the weights h_k: G_k <= 0 for every k implies the
virtual system contracts for ANY convex combination sum_k h_k(x) f_k (proof of Theorem 1).
So the mixture's means, covariances and priors can be optimised freely for accuracy, by a
smooth local optimiser, alternating with the convex dynamics step (metric fixed); the cost
is non-increasing and every iterate stays certified.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular
from scipy.optimize import minimize
from scipy.special import logsumexp

from sosdyn.poly import monomial_values
from .contraction import eval_fields
from .gmm import PositionMixture
from .steps import DynamicsStep, LeastSquaresData


def _pack(mix: PositionMixture) -> np.ndarray:
    K, n = mix.means.shape
    tril = np.tril_indices(n)
    chols = np.linalg.cholesky(mix.covariances)
    diag = np.arange(n)
    chols[:, diag, diag] = np.log(chols[:, diag, diag])
    return np.concatenate([mix.means.ravel(), chols[:, tril[0], tril[1]].ravel(), np.log(mix.weights)])


def _unpack_factors(theta: np.ndarray, K: int, n: int):
    """(weights, means, Cholesky factors L_k) of the parameter vector (see _pack)."""
    tril = np.tril_indices(n)
    t = len(tril[0])
    means = theta[:K * n].reshape(K, n)
    L = np.zeros((K, n, n))
    L[:, tril[0], tril[1]] = theta[K * n:K * n + K * t].reshape(K, t)
    diag = np.arange(n)
    L[:, diag, diag] = np.exp(np.clip(L[:, diag, diag], -20, 20))
    logw = theta[K * n + K * t:]
    w = np.exp(logw - logw.max())
    return w / w.sum(), means, L


def _unpack(theta: np.ndarray, K: int, n: int) -> PositionMixture:
    w, means, L = _unpack_factors(theta, K, n)
    return PositionMixture(w, means, L @ np.swapaxes(L, 1, 2))


def cost_and_gradient(theta, Z, Zdot, F):
    """cost = mean_t |sum_k h_tk F_tk - zdot_t|^2 and its exact gradient in theta (see _pack).

    With s_tk = log pi_k + log N(z_t; mu_k, L_k L_k^T), h = softmax(s):
      dcost/ds_tk = (2/T) r_t . h_tk (F_tk - f_t),
      dcost/dmu_k = Sigma_k^-1 sum_t g_tk (z_t - mu_k),
      dcost/dL_k  = sum_t g_tk (L_k^-T u_t u_t^T - diag(1/L_ii)),  u_t = L_k^-1 (z_t - mu_k),
      dcost/da_k  = sum_t g_tk  (a: prior logits; sum_k g_tk = 0).
    """
    T, K, n = F.shape
    weights, means, Ls = _unpack_factors(theta, K, n)      # the factors themselves: no re-factoring
    tril = np.tril_indices(n)
    s = np.empty((T, K))
    Us = []
    for k in range(K):
        L = Ls[k]
        U = solve_triangular(L, (Z - means[k]).T, lower=True)
        s[:, k] = np.log(weights[k]) - 0.5 * (U * U).sum(0) - np.log(np.diag(L)).sum()
        Us.append(U)
    h = np.exp(s - logsumexp(s, axis=1, keepdims=True))
    f = np.einsum("tk,tki->ti", h, F)
    r = f - Zdot
    cost = float((r * r).sum() / T)
    g = (2.0 / T) * h * np.einsum("ti,tki->tk", r, F - f[:, None, :])
    g_mu, g_L = np.zeros((K, n)), np.zeros((K, len(tril[0])))
    for k in range(K):
        L, U = Ls[k], Us[k]
        Ug = U @ g[:, k]
        g_mu[k] = solve_triangular(L.T, Ug, lower=False)
        GL = solve_triangular(L.T, (U * g[:, k]) @ U.T, lower=False) - g[:, k].sum() * np.diag(1.0 / np.diag(L))
        GL[np.diag_indices(n)] *= np.diag(L)          # log-parametrised diagonal
        g_L[k] = GL[tril]
    return cost, np.concatenate([g_mu.ravel(), g_L.ravel(), g.sum(axis=0)])


def _well_posed(mix: PositionMixture, max_condition: float = 1e10) -> bool:
    """Covariances that factor and are not numerically singular (else refinement stops)."""
    try:
        np.linalg.cholesky(mix.covariances)
    except np.linalg.LinAlgError:
        return False
    return bool(np.linalg.cond(mix.covariances).max() < max_condition)


def refine_mixture(Z, Zdot, mixture: PositionMixture, C, fexps, dyn: DynamicsStep, record,
                   rounds: int = 3, maxiter: int = 40):
    """Alternate (mixture | fields fixed) and (fields | mixture, metric fixed): ``rounds`` times
    L-BFGS on the mixture (at most ``maxiter`` iterations), each followed by ``dyn.refit``.

    Stops early when a round does not lower the cost or gives an ill-posed mixture. Each
    accepted round is reported as ``record(step, cost, sol=None)``. Returns the new
    (mixture, C); the arguments are not modified.
    """
    K, n = mixture.n_components, Z.shape[1]
    Phi = monomial_values(Z, fexps)
    for _ in range(rounds):
        F = eval_fields(C, fexps, Z)                                          # (T, K, n)
        theta0 = _pack(mixture)
        before = cost_and_gradient(theta0, Z, Zdot, F)[0]
        res = minimize(cost_and_gradient, theta0, args=(Z, Zdot, F), jac=True, method="L-BFGS-B",
                       options={"maxiter": maxiter})
        candidate = _unpack(res.x, K, n)
        if not np.isfinite(res.fun) or res.fun >= before or not _well_posed(candidate):
            break
        mixture = candidate
        record("gmm refinement", res.fun)
        data = LeastSquaresData(mixture.responsibilities(Z), Phi, Zdot)
        C, sol = dyn.refit(data)
        record("dynamics", data.cost(C), sol)
    return mixture, C

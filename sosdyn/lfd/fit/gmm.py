"""The GMM of the motion model (paper eq. 2): joint mixture on [x, xdot] and its position marginal.

    xdot = sum_k h_k(x) (A_k x + b_k),   A_k = S_k,xdot x S_k,xx^-1,  b_k = mu_k,xdot - A_k mu_k,x
    h_k(x) = pi_k N(x; mu_k,x, S_k,xx) / sum_i pi_i N(x; mu_i,x, S_i,xx)

Off the data the weights are tempered (:class:`PositionMixture`, ``bound`` c): with the squared
Mahalanobis distances d_k^2(x) = |L_k^-1 (x - mu_k)|^2 and tau(x) = max(1, min_k d_k^2(x) / c),

    h_k(x) = softmax_k(log pi_k - sum_i log L_k,ii - n/2 log 2 pi - 1/2 d_k^2(x) / tau(x)),

the same numbers, bit for bit, where min_k d_k^2 <= c (tau = 1: every training point, by the
choice of c in :func:`gate_bound`), and off the data a softmax of c (d_k / d_min)^2 that turns
with the direction of x rather than jumping from 0 to 1 across a Voronoi face of the thin
Gaussians (docs/findings.md, 7-D kinks). That softmax keeps its sharpness c in the ratios at every
distance: far off, the weights still switch between cones. The *smooth* gating (``fade`` F, the
default of CDSP with F = FADE) keeps those weights up to tau = F and beyond flattens the whole
tempered log-likelihood by tau / F:

    l_k(x) = log pi_k + (t_k(x) - log pi_k) / max(1, tau(x) / F),   t_k = c_k - d_k^2 / (2 tau)

(t_k the tempered log-joint above, c_k its log normaliser): the tempered numbers, bit for bit, where
tau <= F (the posterior's where tau = 1), and h -> pi (constant weights: one linear field) as
|x| -> inf, since t_k - log pi_k stays bounded while tau grows like |x|^2. F = 3 (FADE): on the 7-joint
reach of docs/findings.md every joint's acceleration stays within a Panda's limits from starts
0.2-0.3 rad off (the tempered weights exceed them up to 3.7 fold), and LASA's held-out starts, at
tau <= 5, keep their reproductions (fading from tau = 1 on, as tau^2, cost 6 % on the swapped split).
The certificate does not involve the weights (it holds for any h in the simplex along any trajectory;
docs/theory.md), so it holds for every gating.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import chdtri

from sosdyn.errors import InputError

MAX_BIC_COMPONENTS = 10         # n_components="bic" tries K = 1..10
MIN_SAMPLES_PER_COMPONENT = 5   # and needs at least 5 samples per Gaussian
GATE_QUANTILE = 0.999           # the gating's bound is at least the chi^2_n quantile of this level
FADE = 3.0                      # the smooth gating fades to pi beyond tau = FADE (module docstring)


def check_joint_gmm(gmm, n: int) -> None:
    """A fitted full-covariance sklearn GaussianMixture on [x, xdot] with x of dimension n."""
    if getattr(gmm, "covariance_type", None) != "full" or not hasattr(gmm, "means_"):
        raise InputError("expected a fitted sklearn GaussianMixture with covariance_type='full'.")
    if gmm.means_.shape[1] != 2 * n:
        raise InputError(f"the mixture is {gmm.means_.shape[1]}-D, expected 2*n = {2 * n} for "
                         f"[x, xdot] with n = {n}; pass the position dimension n.")


def gmm_linear_maps(gmm, n: int):
    """Per-component linear maps of eq. (2): A (K, n, n) and b (K, n)."""
    check_joint_gmm(gmm, n)
    cov, mean = gmm.covariances_, gmm.means_
    A = np.linalg.solve(cov[:, :n, :n], cov[:, :n, n:]).transpose(0, 2, 1)   # S_xx^-1 S_x,xdot = A^T
    b = mean[:, n:] - np.einsum("kij,kj->ki", A, mean[:, :n])
    return A, b


def fit_joint_gmm(Z, Zdot, n_components, seed: int):
    """EM on the joint samples [z, zdot]: (sklearn GaussianMixture, BIC list or None).

    ``n_components`` is K, or "bic" for the K in 1..MAX_BIC_COMPONENTS (at most one per
    MIN_SAMPLES_PER_COMPONENT samples) with the lowest Bayesian information criterion."""
    from sklearn.mixture import GaussianMixture     # lazy: importing sklearn takes seconds; only fits need it
    from threadpoolctl import threadpool_limits     # (sklearn's own dependency)

    data = np.hstack([Z, Zdot])

    def em(k):
        # one OpenMP thread: k-means on a few thousand samples gains nothing from more, and on a
        # busy machine its spinning threads cost ~1 s per fit (issue 14); the result is identical
        with threadpool_limits(1, user_api="openmp"):
            return GaussianMixture(k, covariance_type="full", random_state=seed, reg_covar=1e-6,
                                   max_iter=500).fit(data)
    if n_components != "bic":
        return em(n_components), None
    top = min(MAX_BIC_COMPONENTS, Z.shape[0] // MIN_SAMPLES_PER_COMPONENT)
    fits = [em(k) for k in range(1, top + 1)]
    bic = [float(g.bic(data)) for g in fits]
    return fits[int(np.argmin(bic))], bic


def gmr_cost(gmm, Z, Zdot) -> float:
    """Cost (18) of the unconstrained GMR of ``gmm``: mean_t |sum_k h_k(z_t)(A_k z_t + b_k) - zdot_t|^2,
    the accuracy ceiling of this GMM."""
    n = Z.shape[1]
    A, b = gmm_linear_maps(gmm, n)
    H = PositionMixture.from_joint(gmm, n).responsibilities(Z)
    pred = np.einsum("tk,kij,tj->ti", H, A, Z) + H @ b
    return float(((pred - Zdot) ** 2).sum() / Z.shape[0])


@dataclass
class PositionMixture:
    """pi_k, mu_k,x, S_k,xx of the position marginal and the gating's bound c: all h_k(x) needs.

    ``bound`` None: the plain posterior; a number c > 0: tempered where min_k d_k^2 > c, and with a
    ``fade`` F (None: none) faded to pi beyond tau = F (module docstring). Treat it as immutable: the
    Cholesky factors are computed once, on first use.
    """

    weights: np.ndarray       # (K,)
    means: np.ndarray         # (K, n)
    covariances: np.ndarray   # (K, n, n)
    bound: float | None = None
    fade: float | None = None

    @classmethod
    def from_joint(cls, gmm, n: int) -> "PositionMixture":
        check_joint_gmm(gmm, n)
        return cls(gmm.weights_.copy(), gmm.means_[:, :n].copy(), gmm.covariances_[:, :n, :n].copy())

    @property
    def n_components(self) -> int:
        return self.weights.size

    def factors(self):
        """Inverse Cholesky factors and log normalisers, computed once per mixture."""
        if getattr(self, "_cache", None) is None:
            n = self.means.shape[1]
            chol = np.linalg.cholesky(self.covariances)
            inv = np.linalg.inv(chol)
            lognorm = (np.log(self.weights) - np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
                       - 0.5 * n * np.log(2 * np.pi))
            self._cache = (inv, lognorm)
        return self._cache

    def log_joint(self, X: np.ndarray) -> np.ndarray:
        """log pi_k + log N(x; mu_k, S_k) at the rows of X: shape (m, K); with a ``bound`` tempered
        by tau(x) (:func:`gated`; module docstring; the same numbers exactly where tau = 1).

        Far from the data the quadratic form overflows and an entry is -inf (NaN when
        ``x - mu_k`` itself overflows, or every form overflows under a bound); :meth:`responsibilities`
        handles both.
        """
        inv, lognorm = self.factors()
        with np.errstate(over="ignore", invalid="ignore"):
            z = np.einsum("kij,mkj->mki", inv, X[:, None, :] - self.means[None])
            return gated(np.einsum("mki,mki->mk", z, z), lognorm[None, :], np.log(self.weights)[None, :], self.bound,
                         self.fade)

    def far_weights(self, X: np.ndarray) -> np.ndarray:
        """h at rows of X where :meth:`log_joint` has no finite entry or a NaN (the forms overflow):
        without a bound one-hot on the component of least Mahalanobis distance (the softmax's limit),
        with a bound c the exact tempered weights softmax_k(c_k - c/2 (d_k / d_min)^2), the distance
        ratios from :meth:`log_mahalanobis` (finite for any finite x); with a fade, pi (the limit:
        tau overflows too)."""
        if self.bound is not None and self.fade is not None:
            return np.repeat(self.weights[None, :], len(X), axis=0)
        logd = self.log_mahalanobis(X)
        if self.bound is None:
            return np.eye(self.n_components)[np.argmin(logd, axis=1)]
        lj = self.factors()[1][None, :] - 0.5 * self.bound * np.exp(2.0 * (logd - logd.min(axis=1, keepdims=True)))
        return np.exp(lj - log_sum_exp(lj))

    def log_mahalanobis(self, X: np.ndarray) -> np.ndarray:
        """log ||S_k^-1/2 (x - mu_k)|| at the rows of X, shape (m, K), finite for any finite x.

        Each row is divided by c = max(1, max_i |x_i|) before the triangular solve, so
        nothing overflows: log d_k(x) = log c + 1/2 log ||L_k^-1 (x/c - mu_k/c)||^2.
        """
        inv, _ = self.factors()
        c = np.maximum(np.abs(X).max(axis=1), 1.0)[:, None, None]
        z = np.einsum("kij,mkj->mki", inv, X[:, None, :] / c - self.means[None] / c)
        with np.errstate(divide="ignore"):
            return np.log(c[:, :, 0]) + 0.5 * np.log(np.einsum("mki,mki->mk", z, z))

    def responsibilities(self, X: np.ndarray) -> np.ndarray:
        """h_k(x) = pi_k N(x; mu_k, S_k) / sum_i pi_i N(x; mu_i, S_i), shape (m, K), rows sum to one.

        Computed in log-space: h = exp(l - logsumexp(l)), l_k = log pi_k + log N(x; mu_k, S_k).
        With a ``bound``, tempered off the data (module docstring). Where every l_k underflows (the
        quadratic forms overflow float, ||x|| ~ 1e154 and up) :meth:`far_weights`: without a bound
        one-hot on the component nearest in Mahalanobis distance (:meth:`log_mahalanobis`), the
        limit of the softmax as the quadratic terms dominate log pi_k and the normalisers.
        Raises :class:`InputError` for rows of X that are NaN or inf.
        """
        return responsibilities_of([self], [X])[0]


def gated(q: np.ndarray, lognorm: np.ndarray, logw: np.ndarray, bound, fade) -> np.ndarray:
    """The log-joints l (m, K) from the quadratic forms q (m, K), the log normalisers c_k and log pi_k
    (rows (1, K) or (m, K)): the posterior's c_k - q_k / 2 without a ``bound``; with one, row by row
    (module docstring) tempered, t_k = c_k - q_k / (2 tau) with tau = max(1, min_k q_k / bound), and with
    a ``fade`` F where tau > F, log pi_k + (t_k - log pi_k) F / tau. ``bound`` None, a number, or a column
    (m, 1) of per-row bounds (inf: not tempered); ``fade`` None, a number, or a column of them (inf: no
    fade). A tempered row with a form that is not finite becomes NaN (its weights are
    :meth:`PositionMixture.far_weights`, exact there)."""
    if bound is None:
        return lognorm - 0.5 * q
    with np.errstate(over="ignore", invalid="ignore"):
        tau = np.maximum(1.0, q.min(axis=1, keepdims=True) / bound)
        out = lognorm - 0.5 * (q / tau)                 # q / 1.0 = q: the posterior's numbers where tau = 1
        if fade is not None:
            out = np.where(tau <= fade, out, logw + (out - logw) / (tau / fade))
        return np.where(np.isfinite(q).all(axis=1, keepdims=True) | ~np.isfinite(bound), out, np.nan)


def gate_bound(mixture: PositionMixture, U: np.ndarray, quantile: float = GATE_QUANTILE) -> float:
    """The gating's bound c for ``mixture`` fitted on the rows of U: the larger of the chi^2_n
    ``quantile`` and max_t min_k d_k^2(u_t), so that every training point (and every state as near
    to a Gaussian) gets the plain posterior, bit for bit."""
    inv, _ = mixture.factors()
    z = np.einsum("kij,mkj->mki", inv, U[:, None, :] - mixture.means[None])
    chi2_quantile = chdtri(U.shape[1], 1.0 - quantile)         # P(chi^2_n > x) = 1 - quantile
    return float(max(chi2_quantile, np.einsum("mki,mki->mk", z, z).min(axis=1).max()))


def with_bound(mixture: PositionMixture, bound: float | None, fade: float | None = None) -> PositionMixture:
    """``mixture`` with the gating's bound ``bound`` and ``fade`` (a new object: factors are recomputed
    once)."""
    return PositionMixture(mixture.weights, mixture.means, mixture.covariances, bound, fade)


def responsibilities_of(mixtures: list, blocks: list) -> list[np.ndarray]:
    """:meth:`PositionMixture.responsibilities` of ``mixtures[b]`` at the rows of ``blocks[b]``, for
    every b, with one log-sum-exp over all rows (:func:`log_sum_exp`): the log-joints padded with
    -inf to the largest K (exact zeros in every sum), so each block's numbers are its mixture's own
    (at round-off when the K differ: the sums' association may change)."""
    L = []
    for mix, X in zip(mixtures, blocks):
        X = np.asarray(X, dtype=float)
        n = mix.means.shape[1]
        if X.ndim != 2 or X.shape[1] != n or not np.isfinite(X).all():
            bad = np.flatnonzero(~np.isfinite(X).all(axis=1)) if X.ndim == 2 and X.shape[1] == n else []
            what = f"row {bad[0]} = {X[bad[0]]} is not finite" if len(bad) else f"has shape {X.shape}"
            raise InputError(f"responsibilities: X {what}; pass finite states of shape (m, {n}).")
        L.append(mix.log_joint(X))
    return weights_from(L, mixtures, blocks)


def block_log_joint(mixtures: list, rows: int):
    """``log_joint(X)``: :meth:`PositionMixture.log_joint` of ``mixtures[b]`` at the b-th block of
    ``rows`` rows of X (all mixtures of one K and n), every block in one pass (each row with its
    mixture's factors; the same numbers as block by block, checked in the tests)."""
    each = lambda a: np.repeat(np.array([a(mix) for mix in mixtures]), rows, axis=0)   # noqa: E731
    inv, means, lognorm = each(lambda m: m.factors()[0]), each(lambda m: m.means), each(lambda m: m.factors()[1])
    logw = each(lambda m: np.log(m.weights))
    bound = None if all(m.bound is None for m in mixtures) else \
        each(lambda m: np.inf if m.bound is None else m.bound)[:, None]     # tempered rows (module docstring)
    fade = None if all(m.fade is None for m in mixtures) else \
        each(lambda m: np.inf if m.fade is None else m.fade)[:, None]

    def log_joint(X):
        with np.errstate(over="ignore", invalid="ignore"):
            z = np.einsum("mkij,mkj->mki", inv, X[:, None, :] - means)
            return gated(np.einsum("mki,mki->mk", z, z), lognorm, logw, bound, fade)
    return log_joint


def weights_from(L: list, mixtures: list, blocks: list) -> list[np.ndarray]:
    """:func:`responsibilities_of` from the blocks' log-joints ``L`` (checked finite rows)."""
    K = max(mix.n_components for mix in mixtures)
    if len(L) == 1 or all(lb.shape[1] == K for lb in L):
        lj = L[0] if len(L) == 1 else np.concatenate(L)
    else:
        lj, rows = np.full((sum(len(lb) for lb in L), K), -np.inf), np.cumsum([0] + [len(lb) for lb in L])
        for lb, r in zip(L, rows):
            lj[r:r + len(lb), :lb.shape[1]] = lb
    far = None if np.isfinite(lj).all() else ~np.isfinite(lj).any(axis=1) | np.isnan(lj).any(axis=1)
    if far is not None:
        lj[far] = 0.0
    h = np.exp(lj - log_sum_exp(lj))
    out, start = [], 0
    for mix, X, lb in zip(mixtures, blocks, L):
        hb = h[start:start + len(lb), :mix.n_components]
        fb = None if far is None else far[start:start + len(lb)]
        if fb is not None and fb.any():
            hb[fb] = mix.far_weights(np.asarray(X, float)[fb])
        out.append(hb)
        start += len(lb)
    return out


def log_sum_exp(A: np.ndarray) -> np.ndarray:
    """log sum_k exp(a_k) of every row of A (N, K) with a finite maximum, as a column (N, 1): with
    M = max_k a_k attained c times, log1p(s / c) + log c + M, s = sum over the other entries of
    exp(a_k - M) (scipy.special.logsumexp's formula, operation for operation: the same numbers)."""
    top = A.max(axis=1, keepdims=True)
    at_top = A == top
    c = at_top.sum(axis=1, keepdims=True, dtype=A.dtype)
    s = np.exp(np.where(at_top, -np.inf, A) - top).sum(axis=1, keepdims=True, dtype=A.dtype)
    return np.log1p(np.where(s == 0, s, s / c)) + np.log(c) + top
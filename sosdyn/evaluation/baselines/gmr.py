"""GMR baseline: a Gaussian mixture on [x, ẋ] regressed to E[ẋ | x] (no stability guarantee).

The mixture p(x, ẋ) = Σ_k π_k N([x, ẋ]; μ_k, Σ_k) gives the field of the CDSP paper, Eq. (2):

    ẋ = f(x) = Σ_k h_k(x) (A_k x + b_k),
    A_k = Σ_k,ẋx Σ_k,xx⁻¹,   b_k = μ_k,ẋ − A_k μ_k,x,
    h_k(x) = π_k N(x; μ_k,x, Σ_k,xx) / Σ_i π_i N(x; μ_i,x, Σ_i,xx).

:func:`gmm_linear_maps` and :func:`position_responsibilities` are public because the CDSP
learner starts from the same quantities.
"""

import numpy as np
from scipy.linalg import solve_triangular
from scipy.special import logsumexp
from sklearn.mixture import GaussianMixture

from sosdyn.errors import InputError
from sosdyn.evaluation.baselines.base import AutonomousModel, check_int, check_points, \
    check_positive


def _check_joint_gmm(gmm, n):
    if getattr(gmm, "covariance_type", None) != "full" or not hasattr(gmm, "means_"):
        raise InputError(
            "expected a fitted sklearn GaussianMixture with covariance_type='full'.")
    if gmm.means_.shape[1] != 2 * n:
        raise InputError(
            f"the mixture is {gmm.means_.shape[1]}-D, expected 2*n = {2 * n} for "
            f"[x, ẋ] with n = {n}; pass the position dimension n.")


def gmm_linear_maps(gmm, n):
    """Per-component linear maps of Eq. (2): A (K, n, n) and b (K, n).

    A_k = Σ_k,ẋx Σ_k,xx⁻¹ and b_k = μ_k,ẋ − A_k μ_k,x for a full-covariance mixture on
    [x, ẋ] whose first ``n`` coordinates are the position.
    """
    _check_joint_gmm(gmm, n)
    cov, mean = gmm.covariances_, gmm.means_
    # A_kᵀ = Σ_xx⁻¹ Σ_xẋ because Σ_xx is symmetric.
    A = np.linalg.solve(cov[:, :n, :n], cov[:, :n, n:]).transpose(0, 2, 1)
    b = mean[:, n:] - np.einsum("kij,kj->ki", A, mean[:, :n])
    return A, b


def position_responsibilities(gmm, X, n):
    """h_k(x) of Eq. (2) at the rows of ``X`` (m, n): shape (m, K), rows sum to one.

    Computed in log space, log π_k + log N(x; μ_k,x, Σ_k,xx) normalised with logsumexp,
    so points far from every component still get well-defined weights.
    """
    _check_joint_gmm(gmm, n)
    X = check_points(X, n)
    log_joint = np.empty((X.shape[0], gmm.n_components))
    for k in range(gmm.n_components):
        chol = np.linalg.cholesky(gmm.covariances_[k, :n, :n])
        z = solve_triangular(chol, (X - gmm.means_[k, :n]).T, lower=True)
        log_joint[:, k] = (np.log(gmm.weights_[k]) - 0.5 * np.sum(z * z, axis=0)
                           - np.sum(np.log(np.diag(chol))) - 0.5 * n * np.log(2 * np.pi))
    return np.exp(log_joint - logsumexp(log_joint, axis=1, keepdims=True))


class GMR(AutonomousModel):
    """Gaussian mixture regression ẋ = E[ẋ | x] of Eq. (2), fitted by EM (scikit-learn).

    Parameters
    ----------
    n_components : int
        K, the number of Gaussians.
    random_state : int
        Seed of the k-means initialisation of EM (fixed for reproducible fits).
    reg_covar : float
        Added to the diagonal of each covariance (data units²).
    max_iter : int
        EM iterations.

    A goal change translates the field: f_g(x) = f(x − g + g_train).
    Learned attributes: ``gmm_``, ``A_`` (K, n, n), ``b_`` (K, n), ``goal_``, ``dim_``, ``dt_``.
    """

    name = "GMR"

    def __init__(self, n_components=6, random_state=0, reg_covar=1e-6, max_iter=500):
        self.n_components = n_components
        self.random_state = random_state
        self.reg_covar = reg_covar
        self.max_iter = max_iter

    def fit(self, demos):
        k = check_int(self.n_components, "n_components")
        demos = self._learn_frame(demos)
        X, Xdot = demos.stacked()
        if X.shape[0] < 2 * k:
            raise InputError(
                f"{X.shape[0]} data points are too few for {k} Gaussians; "
                "use fewer components or more demonstrations.")
        self.gmm_ = GaussianMixture(
            n_components=k, covariance_type="full", random_state=self.random_state,
            reg_covar=check_positive(self.reg_covar, "reg_covar"),
            max_iter=check_int(self.max_iter, "max_iter")).fit(np.hstack([X, Xdot]))
        self.A_, self.b_ = gmm_linear_maps(self.gmm_, self.dim_)
        return self

    def responsibilities(self, X):
        """h_k(x) at the rows of ``X`` (m, n), shape (m, K)."""
        self._check_fitted()
        return position_responsibilities(self.gmm_, X, self.dim_)

    def field(self, X, goal):
        """Eq. (2) translated to ``goal``: Σ_k h_k(x̄)(A_k x̄ + b_k), x̄ = x − goal + goal_."""
        Xs = X - goal + self.goal_
        h = position_responsibilities(self.gmm_, Xs, self.dim_)
        return np.einsum("mk,kij,mj->mi", h, self.A_, Xs) + h @ self.b_

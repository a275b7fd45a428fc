"""GMR baseline: a Gaussian mixture on [x, ẋ] regressed to E[ẋ | x] (no stability guarantee).

The mixture p(x, ẋ) = Σ_k π_k N([x, ẋ]; μ_k, Σ_k) gives the field of the CDSP paper, Eq. (2):

    ẋ = f(x) = Σ_k h_k(x) (A_k x + b_k),
    A_k = Σ_k,ẋx Σ_k,xx⁻¹,   b_k = μ_k,ẋ − A_k μ_k,x,
    h_k(x) = π_k N(x; μ_k,x, Σ_k,xx) / Σ_i π_i N(x; μ_i,x, Σ_i,xx).

:func:`gmm_linear_maps` lives in :mod:`sosdyn.lfd.fit.gmm` (the CDSP learner starts from it).
"""

import numpy as np
from sklearn.mixture import GaussianMixture

from sosdyn.errors import InputError
from sosdyn.lfd.fit.gmm import PositionMixture, gmm_linear_maps
from sosdyn.evaluation.baselines.base import AutonomousModel, check_int, check_points
from sosdyn.lfd.rollout import as_positive


def position_responsibilities(gmm, X, n):
    """h_k(x) of Eq. (2) at the rows of ``X`` (m, n): shape (m, K), rows sum to one."""
    return PositionMixture.from_joint(gmm, n).responsibilities(check_points(X, n))


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
            reg_covar=as_positive(self.reg_covar, "reg_covar"),
            max_iter=check_int(self.max_iter, "max_iter")).fit(np.hstack([X, Xdot]))
        self.A_, self.b_ = gmm_linear_maps(self.gmm_, self.dim_)
        self.mixture_ = PositionMixture.from_joint(self.gmm_, self.dim_)   # factors cached once
        return self

    def responsibilities(self, X):
        """h_k(x) at the rows of ``X`` (m, n), shape (m, K)."""
        self._check_fitted()
        return self.mixture_.responsibilities(check_points(X, self.dim_))

    def field(self, X, goal):
        """Eq. (2) translated to ``goal``: Σ_k h_k(x̄)(A_k x̄ + b_k), x̄ = x − goal + goal_."""
        Xs = X - goal + self.goal_
        h = self.mixture_.responsibilities(Xs)
        return np.einsum("mk,kij,mj->mi", h, self.A_, Xs) + h @ self.b_

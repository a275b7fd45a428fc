"""The CDSP estimator: contracting dynamical system primitives (Ravichandar et al.).

Model (eq. 2, goal-shifted and scaled, z = (x - x*)/s):  zdot = sum_k h_k(z) f_k(z),
f_k(0) = 0 (eq. 5). Guarantee (eq. 4/9, SOS form eq. 14-19): for every k,
-G_k(z) = -(J_k^T M + M J_k + dM[f_k] + gamma M) is an SOS matrix and M - eps I is an SOS
matrix, so the virtual system ydot = sum_k h_k(x) f_k(y) contracts in the metric M at rate
gamma whatever the weights h_k, and every trajectory converges to x* (Theorem 1).

Why the paper's polynomial metric adds nothing for linear sub-systems: with f_k = A_k z,
dM(z)[A_k z] vanishes at z = 0, so evaluating (4) at z = 0 gives
A_k^T M(0) + M(0) A_k + gamma M(0) <= 0 -- the constant metric M(0) certifies every A_k
that M(z) certifies. The learner measures this (``metric_collapse_``). With polynomial
sub-systems (``field_degree`` 3) the state-dependent metric does matter.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from ..errors import InputError, NotCertifiedError, NotFittedError, SolverError
from .certificate import CertificateReport, check_model, extract_certificate
from .data import check_demonstrations
from .fields import (eval_fields, field_exponents, metric_exponents, monomial_values)
from .gmm import PositionMixture, gmm_linear_maps
from .rollout import rollout as integrate
from .steps import DynamicsStep, ICAStep, LeastSquaresData, MetricStep, certify

METHODS = ("alternating", "ica")


class CDSP:
    """Learn a partially contracting dynamical system from demonstrations.

    Parameters
    ----------
    n_components : int or "bic"  K, Gaussians of the GMM (paper: 6/7/6/6); "bic" picks K in 1..10
                                 by the Bayesian information criterion of EM fits.
    metric_degree : int          degree of M(z) (0 = constant metric; even).
    field_degree : int           degree of the sub-systems f_k (1 = the paper's A_k x + b_k; odd).
    gamma : float                contraction rate (1/s, in the data's time units).
    metric : {"learned", "identity"}   "identity" fixes M = I (SEDS-like quadratic Lyapunov).
    solver : str                 conic solver ("CLARABEL"; "SCS" via cvxpy).
    solver_method : {"alternating", "ica"}   plain alternation, or the inner convex approximation.
    max_iter, tol                alternation / ICA iterations and relative cost tolerance.
    eps, margin                  M >= eps I; the trained fields satisfy -G_k >= margin I.
    refine_gmm : bool            also optimise the GMM's position means/covariances (paper's theta_G).
    max_samples : int or None    subsample the data to at most this many points (EM and fit).
    random_state : int           seed of EM and of the verification samples.
    allow_uncertified : bool     return a model whose check failed (flagged) instead of raising.

    Learned attributes end in ``_``: ``goal_``, ``scale_``, ``mixture_``, ``C_`` (K, n, m),
    ``W_`` (n, n, p), ``history_``, ``certificate_``, ``verification_``, ``metric_collapse_``.
    """

    name = "CDSP"

    def __init__(self, n_components=6, metric_degree=0, field_degree=1, gamma=0.1, metric="learned",
                 solver="CLARABEL", solver_method="alternating", max_iter=20, tol=1e-4, eps=1e-3,
                 margin=1e-4, refine_gmm=False, max_samples=3000, random_state=0,
                 verify_samples=10_000, allow_uncertified=False, progress=None):
        self.n_components = n_components
        self.metric_degree = metric_degree
        self.field_degree = field_degree
        self.gamma = gamma
        self.metric = metric
        self.solver = solver
        self.solver_method = solver_method
        self.max_iter = max_iter
        self.tol = tol
        self.eps = eps
        self.margin = margin
        self.refine_gmm = refine_gmm
        self.max_samples = max_samples
        self.random_state = random_state
        self.verify_samples = verify_samples
        self.allow_uncertified = allow_uncertified
        self.progress = progress

    # ------------------------------------------------------------------ parameters
    def get_params(self) -> dict:
        keys = ("n_components", "metric_degree", "field_degree", "gamma", "metric", "solver",
                "solver_method", "max_iter", "tol", "eps", "margin", "refine_gmm", "max_samples",
                "random_state", "verify_samples", "allow_uncertified")
        return {k: getattr(self, k) for k in keys}

    def _check_params(self):
        def integer(name, lo):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise InputError(f"{name} must be an integer >= {lo}, got {v!r}")
        if self.n_components != "bic":
            integer("n_components", 1)
        integer("metric_degree", 0)
        integer("field_degree", 1)
        integer("max_iter", 0)
        if self.metric_degree % 2:
            raise InputError(f"metric_degree={self.metric_degree} is odd: a polynomial metric of odd "
                             "degree cannot be positive definite for all x; use 0, 2 or 4")
        if self.field_degree % 2 == 0:
            raise InputError(
                f"field_degree={self.field_degree} is even: the contraction condition then has odd "
                f"degree {self.metric_degree + self.field_degree - 1} in x and its leading part cannot "
                "be negative definite, so no certificate exists; use field_degree 1 or 3")
        for name in ("gamma", "eps", "tol"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
                raise InputError(f"{name} must be a positive number, got {v!r}")
        if self.metric not in ("learned", "identity"):
            raise InputError(f"metric must be 'learned' or 'identity', got {self.metric!r}")
        if self.solver_method not in METHODS:
            raise InputError(f"solver_method must be one of {METHODS}, got {self.solver_method!r}")
        if self.solver_method == "ica" and self.metric == "identity":
            raise InputError("solver_method='ica' learns the metric; with metric='identity' there is "
                             "nothing to alternate: use solver_method='alternating'")

    # ------------------------------------------------------------------ coordinates
    def _to_z(self, X):
        return (X - self.goal_) / self.scale_

    def _record(self, step, cost, sol=None, **extra):
        row = {"iteration": len(self.history_), "step": step, "cost": float(cost)}
        if sol is not None:
            row.update(status=sol.status, solve_s=sol.timings["solve"],
                       build_s=sol.timings["build"] + sol.timings["canonicalize"])
            if "fallback" in sol.info:
                row["fallback"] = sol.info["fallback"]
        row.update(extra)
        self.history_.append(row)
        if self.progress is not None:
            self.progress(row)

    # ------------------------------------------------------------------ fitting
    def fit(self, demos):
        """Learn from Demonstrations (validated first); returns self.

        BLAS runs single-threaded inside: every matrix here is small, and a multi-threaded
        OpenBLAS spin-waits on small problems (measured 10-100x slower on 2 loaded cores).
        """
        from threadpoolctl import threadpool_limits
        with threadpool_limits(limits=1, user_api="blas"):
            return self._fit(demos)

    def _fit(self, demos):
        t_start = time.perf_counter()
        self._check_params()
        demos = check_demonstrations(demos)
        X, Xdot = demos.stacked()
        n = demos.dim
        K = 1 if self.n_components == "bic" else int(self.n_components)
        if X.shape[0] < 5 * K:
            raise InputError(f"{X.shape[0]} samples are too few for {K} Gaussians; "
                             "use fewer components or more demonstrations")
        if self.max_samples and X.shape[0] > self.max_samples:
            step = int(np.ceil(X.shape[0] / self.max_samples))
            X, Xdot = X[::step], Xdot[::step]
        self.dim_, self.goal_ = n, np.asarray(demos.goal, dtype=float)
        self.scale_ = float(np.abs(X - self.goal_).max()) or 1.0
        self.dt_ = float(np.median(np.concatenate([np.diff(d.t) for d in demos])))
        self.units_ = demos.units
        Z, Zdot = self._to_z(X), Xdot / self.scale_
        self.history_, self.timings_ = [], {}

        from sklearn.mixture import GaussianMixture    # heavy import, only when fitting

        t0 = time.perf_counter()
        data_xv = np.hstack([Z, Zdot])

        def em(k):
            return GaussianMixture(k, covariance_type="full", random_state=self.random_state,
                                   reg_covar=1e-6, max_iter=500).fit(data_xv)
        if self.n_components == "bic":
            fits = [em(k) for k in range(1, min(10, X.shape[0] // 5) + 1)]
            self.bic_ = [float(g.bic(data_xv)) for g in fits]
            gmm = fits[int(np.argmin(self.bic_))]
        else:
            gmm = em(K)
        self.n_components_ = gmm.n_components
        self.mixture_ = PositionMixture.from_joint(gmm, n)
        self.timings_["em_s"] = time.perf_counter() - t0

        self.field_exps_ = field_exponents(n, self.field_degree)
        self.metric_exps_ = metric_exponents(n, self.metric_degree if self.metric == "learned" else 0)
        self._Z, self._Zdot = Z, Zdot
        data = self._data()
        self.gmr_cost_ = self._gmr_cost(gmm, Z, Zdot)

        t0 = time.perf_counter()
        try:
            self._learn(data)
            if self.refine_gmm:
                self._refine(data)
        except SolverError as exc:
            raise type(exc)(f"CDSP fit failed: {exc.detail}", exc.status,
                            exc.hint or "a smaller gamma, solver_method='alternating', or fewer "
                            "components") from exc
        self.timings_["learn_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        sol = certify(self.C_, self.field_exps_, self.W_, self.metric_exps_, self._vars,
                      self.gamma, 0.5 * self.eps, self.solver)
        self.certificate_ = extract_certificate(sol, 0.5 * self.eps)
        self.timings_["certify_s"] = time.perf_counter() - t0
        self.metric_collapse_ = self._collapse_diagnostic()
        t0 = time.perf_counter()
        self.verification_ = self.verify()
        self.timings_["verify_s"] = time.perf_counter() - t0
        self.timings_["total_s"] = time.perf_counter() - t_start
        self.certified_ = self.verification_.passed
        if not self.certified_:
            msg = f"the learned model's certificate failed its independent check:\n{self.verification_}"
            if not self.allow_uncertified:
                raise NotCertifiedError(msg, "solver_error", "a smaller gamma, a larger margin, or "
                                        "solver='SCS'; or pass allow_uncertified=True to inspect it")
            warnings.warn(msg, stacklevel=2)
        del self._Z, self._Zdot, self._dyn
        return self

    def _data(self, exps=None):
        H = self.mixture_.responsibilities(self._Z)
        exps = self.field_exps_ if exps is None else exps
        return LeastSquaresData(H, monomial_values(self._Z, exps), self._Zdot)

    def _gmr_cost(self, gmm, Z, Zdot):
        """Cost (18) of the unconstrained GMR: the accuracy ceiling of this GMM."""
        A, b = gmm_linear_maps(gmm, self.dim_)
        H = self.mixture_.responsibilities(Z)
        pred = np.einsum("tk,kij,tj->ti", H, A, Z) + H @ b
        return float(((pred - Zdot) ** 2).sum() / Z.shape[0])

    def _learn(self, data):
        """Stage A: linear fields with a constant metric (alternation or ICA).
        Stage B (field_degree > 1 or metric_degree > 0): start from stage A's certified
        (C, P), add the higher-degree terms, and alternate dynamics and metric steps."""
        n = self.dim_
        lin_exps, const_exps = field_exponents(n, 1), metric_exponents(n, 0)
        lin_data = self._data(lin_exps)
        C, P, self._dyn = self._stage_a(lin_data, lin_exps, const_exps)
        if self.field_degree == 1 and (self.metric_degree == 0 or self.metric == "identity"):
            self.C_, self.W_ = C, P[:, :, None]
            return
        C = self._embed(C, lin_exps, self.field_exps_, axis_size=(n,))
        W = self._embed(P[:, :, None], const_exps, self.metric_exps_, axis_size=(n, n))
        dyn = self._dyn = DynamicsStep(data, self.field_exps_, self.metric_exps_, margin=self.margin,
                                       **self._step_args)
        C, sol = dyn.solve(W)
        self._record("dynamics (degree %d)" % self.field_degree, data.cost(C), sol)
        if self.metric == "learned" and self.metric_degree > 0:
            C, W = self._alternate(data, dyn, C, W, self.field_exps_, self.metric_exps_)
        self.C_, self.W_ = C, W

    @property
    def _step_args(self):
        return dict(vars=self._vars, gamma=self.gamma, solver=self.solver)

    def _stage_a(self, data, fexps, mexps):
        n = self.dim_
        dyn = DynamicsStep(data, fexps, mexps, margin=self.margin, **self._step_args)
        W = np.eye(n)[:, :, None]
        C, sol = dyn.solve(W)
        self._record("dynamics (M = I)", data.cost(C), sol)
        if self.metric == "identity":
            return C, np.eye(n), dyn
        if self.solver_method == "alternating":
            C, W = self._alternate(data, dyn, C, W, fexps, mexps)
            return C, W[:, :, 0], dyn
        ica = ICAStep(data, fexps, eps=self.eps, margin=self.margin, **self._step_args)
        P = np.eye(n)
        for _ in range(self.max_iter):
            old = data.cost(C)
            C, P, sol = ica.solve(C, P)
            self._record("ica", data.cost(C), sol)
            C, sol = dyn.solve(P[:, :, None])          # all coefficients under the new metric
            cost = data.cost(C)
            self._record("dynamics", cost, sol)
            if old - cost <= self.tol * max(old, 1e-12):
                break
        return C, P, dyn

    def _alternate(self, data, dyn, C, W, fexps, mexps):
        """Plain alternation: metric step (max margin) then dynamics step, until no progress."""
        used = np.abs(W).max(axis=(0, 1)) > 0
        grow = int(mexps[used].sum(axis=1).max() + fexps.sum(axis=1).max() - 1)
        met = MetricStep(self.dim_, self.n_components_, mexps, fexps, eps=self.eps, grow_degree=grow,
                         **self._step_args)
        for _ in range(self.max_iter):
            W_new, t, sol = met.solve(C)
            self._record("metric", data.cost(C), sol, margin=t)
            if t <= 1e-9:               # no room at all: a fixed point of the alternation
                break
            W, old = W_new, data.cost(C)
            C, sol = dyn.solve(W, margin=0.5 * t, grow_degree=grow)
            cost = data.cost(C)
            self._record("dynamics", cost, sol)
            if old - cost <= self.tol * max(old, 1e-12):
                break
        return C, W

    @staticmethod
    def _embed(coef, exps_from, exps_to, axis_size):
        """Coefficients over ``exps_from`` re-indexed over the larger monomial set ``exps_to``."""
        from ..poly.monomials import match_rows
        out = np.zeros(coef.shape[:-1] + (exps_to.shape[0],))
        out[..., match_rows(exps_to, exps_from)] = coef
        return out

    def _refine(self, data):
        from .refine import refine_mixture
        refine_mixture(self, self._dyn)

    def _collapse_diagnostic(self):
        """Does the constant metric M(0) certify the same fields? (module docstring)."""
        if self.metric != "learned" or self.metric_degree == 0:
            return None
        from .fields import contraction_matrices, generalized_max_eig
        const = int(np.flatnonzero(self.metric_exps_.sum(axis=1) == 0)[0])
        W0 = self.W_[:, :, const:const + 1]
        exps0 = self.metric_exps_[const:const + 1]
        Zs = np.random.default_rng(self.random_state).uniform(-2, 2, size=(2000, self.dim_))
        worst = float(generalized_max_eig(
            contraction_matrices(self.C_, self.field_exps_, W0, exps0, Zs, self.gamma),
            np.repeat(W0[None, :, :, 0], Zs.shape[0], axis=0)).max())
        holds = worst <= 1e-7
        return {"constant_metric_certifies": bool(holds), "max_eig_with_constant_metric": worst,
                "field_degree": int(self.field_degree),
                "note": ("collapse: M(0) alone certifies the learned fields, as it must for linear "
                         "sub-systems (dM[A z] = 0 at z = 0)") if holds and self.field_degree == 1 else
                        ("the state-dependent metric is needed: M(0) alone does not certify the fields"
                         if not holds else "M(0) alone also certifies these fields")}

    # ------------------------------------------------------------------ prediction
    def _check_fitted(self):
        if not hasattr(self, "C_"):
            raise NotFittedError("this CDSP model is not fitted yet; call fit(demos) first")

    def _check_points(self, X, what="X"):
        X = np.asarray(X, dtype=float)
        X = X[None, :] if X.ndim == 1 else X
        if X.ndim != 2 or X.shape[1] != self.dim_:
            raise InputError(f"{what} must have shape (m, {self.dim_}), got {np.shape(X)}")
        if not np.isfinite(X).all():
            raise InputError(f"{what} contains NaN or inf")
        return X

    def field(self, X, goal):
        """xdot at the rows of X for the goal ``goal`` (the field translated to the goal)."""
        Z = (X - goal) / self.scale_
        H = self.mixture_.responsibilities(Z)
        F = eval_fields(self.C_, self.field_exps_, Z)
        return np.einsum("tk,tki->ti", H, F) * self.scale_

    def predict(self, X):
        """Velocities (m, n) at the states X (m, n), in the data's units."""
        self._check_fitted()
        return self.field(self._check_points(X), self.goal_)

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()):
        """Integrate from x0; pushes [(t, dx)] and goal changes [(t, g)] as in sosdyn.lfd.rollout."""
        self._check_fitted()
        x0 = self._check_points(x0, "x0")[0]
        goal = self.goal_ if goal is None else self._check_points(goal, "goal")[0]
        if not (isinstance(duration, (int, float)) and duration > 0):
            raise InputError(f"duration must be a positive number, got {duration!r}")
        return integrate(self.field, x0, duration=float(duration), dt=dt or self.dt_, goal=goal,
                         perturbations=perturbations, goal_changes=goal_changes)

    # ------------------------------------------------------------------ evidence
    def verify(self, n_samples=None, seed=None) -> CertificateReport:
        """Independent check: Gram matrices, and the contraction inequality at sampled states."""
        self._check_fitted()
        return check_model(self, n_samples or self.verify_samples,
                           self.random_state if seed is None else seed)

    def save(self, path):
        from .model_io import save_model
        save_model(self, path)

    @property
    def _vars(self) -> tuple:
        return tuple(f"z{i + 1}" for i in range(self.dim_))

    @property
    def n_iter_(self) -> int:
        return len(self.history_)

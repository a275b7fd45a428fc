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

Model files (:func:`save_model`, :func:`load_model`; the file format is in
:mod:`sosdyn.lfd.model_io`): loading validates every field and re-checks the certificate from
the model's own coefficients with the library's DEFAULT_SAMPLES states. The certificate lives
in z-coordinates and does not involve the weights h_k, so an edited goal, scale or mixture
leaves it valid while changing the motion: only the checksum (accidents) or the keyed
signature (deliberate edits) detect such an edit.
"""
from __future__ import annotations

import inspect
import math
import time
import warnings
from numbers import Integral, Real
from pathlib import Path

import numpy as np

from ..errors import InputError, ModelFileError, NotCertifiedError, NotFittedError, SolverError, SosdynError
from ..sos.program import SOLVERS
from .certificate import (DEFAULT_SAMPLES, CertificateReport, check_model, check_sample_count,
                          extract_certificate)
from .data import check_demonstrations
from .fields import (eval_fields, field_exponents, metric_exponents, monomial_values)
from .gmm import PositionMixture, gmm_linear_maps
from .model_io import (FORMAT, REFIT_HINT, VERSION, array, integer, need, positive, read_model_file,
                       short_string, write_model_file)
from .rollout import rollout as integrate
from .steps import DynamicsStep, ICAStep, LeastSquaresData, MetricStep, certify

METHODS = ("alternating", "ica")
METRICS = ("learned", "identity")
MAX_SEED = 2**32 - 1            # numpy's and sklearn's bound on an integer seed
LOAD_SEED = 0                   # the states of the sampled check when loading a file


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
    solver : str                 conic solver ("CLARABEL"; "SCS" or another solver installed in cvxpy).
    solver_method : {"alternating", "ica"}   plain alternation, or the inner convex approximation.
    max_iter, tol                alternation / ICA iterations and relative cost tolerance.
    eps, margin                  M >= eps I; the trained fields satisfy -G_k >= margin I.
    refine_gmm : bool            also optimise the GMM's position means/covariances (paper's theta_G).
    max_samples : int or None    subsample the data to at most this many points (EM and fit).
    random_state : None, int in [0, 2^32), np.random.Generator or RandomState
                                 seed of EM and of the verification samples; the integer seed
                                 actually used is ``seed_`` (and is what a saved file records).
    verify_samples : int         states of the sampled certificate check, in [100, 10^6].
    allow_uncertified : bool     return a model whose check failed (flagged) instead of raising.
    progress : callable or None  called with each history row while fitting.

    Numbers may be Python or numpy scalars (np.float32, np.int64); booleans are not numbers
    here. Every parameter is checked before any optimisation (InputError saying what to try).

    Learned attributes end in ``_``: ``goal_``, ``scale_``, ``mixture_``, ``C_`` (K, n, m),
    ``W_`` (n, n, p), ``history_``, ``certificate_``, ``verification_``, ``metric_collapse_``.
    """

    name = "CDSP"

    def __init__(self, n_components=6, metric_degree=0, field_degree=1, gamma=0.1, metric="learned",
                 solver="CLARABEL", solver_method="alternating", max_iter=20, tol=1e-4, eps=1e-3,
                 margin=1e-4, refine_gmm=False, max_samples=3000, random_state=0,
                 verify_samples=DEFAULT_SAMPLES, allow_uncertified=False, progress=None):
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
        """Types and ranges of every parameter (no solver is touched: see _check_solver)."""
        def fail(name, want):
            default = inspect.signature(CDSP).parameters[name].default
            raise InputError(f"{name} must be {want}, got {getattr(self, name)!r}. "
                             f"Try: the default, {name}={default!r}.")

        def integer(name, lo):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, Integral) or v < lo:
                fail(name, f"an integer >= {lo}")

        def positive(name):
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, Real) or not np.isfinite(v) or v <= 0:
                fail(name, "a positive finite number")

        def choice(name, options):
            if not isinstance(getattr(self, name), str) or getattr(self, name) not in options:
                fail(name, f"one of {options}")

        if not (isinstance(self.n_components, str) and self.n_components == "bic"):
            if isinstance(self.n_components, str):
                fail("n_components", 'an integer >= 1 or "bic"')
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
        for name in ("gamma", "eps", "tol", "margin"):
            positive(name)
        choice("metric", METRICS)
        choice("solver_method", METHODS)
        if not isinstance(self.solver, str) or not self.solver:
            fail("solver", f"the name of a conic solver, e.g. one of {SOLVERS}")
        if self.max_samples is not None:
            integer("max_samples", 1)
        check_sample_count(self.verify_samples, "verify_samples")
        rs = self.random_state
        if not (rs is None or isinstance(rs, (np.random.Generator, np.random.RandomState))):
            if isinstance(rs, (bool, np.bool_)) or not isinstance(rs, Integral) or not 0 <= rs <= MAX_SEED:
                fail("random_state", f"None, an integer in [0, {MAX_SEED}], a np.random.Generator or a "
                     "np.random.RandomState")
        for name in ("refine_gmm", "allow_uncertified"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                fail(name, "True or False")
        if self.progress is not None and not callable(self.progress):
            fail("progress", "None or a function called with each history row")
        if self.solver_method == "ica" and self.metric == "identity":
            raise InputError("solver_method='ica' learns the metric; with metric='identity' there is "
                             "nothing to alternate: use solver_method='alternating'")

    def _check_solver(self):
        """The solver is one sosdyn drives directly or one installed in cvxpy."""
        if self.solver.upper() in SOLVERS:
            return
        import cvxpy as cp              # heavy: only imported for a solver beyond the defaults
        installed = cp.installed_solvers()
        if self.solver.upper() not in installed:
            raise InputError(f"unknown solver {self.solver!r}; use one of {SOLVERS} or a conic solver "
                             f"installed in cvxpy ({', '.join(installed)}). Try: solver='CLARABEL'.")

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
        self._check_solver()
        demos = check_demonstrations(demos)
        X, Xdot = demos.stacked()
        n = demos.dim
        K = 1 if self.n_components == "bic" else int(self.n_components)
        subsampled = self.max_samples is not None and X.shape[0] > self.max_samples
        if subsampled:
            step = int(np.ceil(X.shape[0] / self.max_samples))
            X, Xdot = X[::step], Xdot[::step]
        if X.shape[0] < 5 * K:
            raise InputError(f"{X.shape[0]} samples{' (after max_samples)' if subsampled else ''} are "
                             f"too few for {K} Gaussians; use fewer components, more demonstrations"
                             f"{' or a larger max_samples' if subsampled else ''}")
        self.seed_ = resolve_seed(self.random_state)
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
            return GaussianMixture(k, covariance_type="full", random_state=self.seed_,
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
        Zs = np.random.default_rng(self.seed_).uniform(-2, 2, size=(2000, self.dim_))
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
        X = self._check_points(X)
        with np.errstate(over="ignore", invalid="ignore"):
            V = self.field(X, self.goal_)
        bad = np.flatnonzero(~np.isfinite(V).all(axis=1))
        if bad.size:
            raise InputError(f"X row {bad[0]} = {X[bad[0]]} is so far from the data (scale {self.scale_:.3g}) "
                             f"that the degree-{self.field_degree} field overflows float. Try: states "
                             "within a few orders of magnitude of the demonstrations.")
        return V

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=()):
        """Integrate from x0; pushes [(t, dx)] and goal changes [(t, g)] as in sosdyn.lfd.rollout.

        ``dt`` None means the model's ``dt_``; duration and dt are checked by the integrator."""
        self._check_fitted()
        x0 = self._check_points(x0, "x0")[0]
        goal = self.goal_ if goal is None else self._check_points(goal, "goal")[0]
        return integrate(self.field, x0, duration=duration, dt=self.dt_ if dt is None else dt, goal=goal,
                         perturbations=perturbations, goal_changes=goal_changes)

    # ------------------------------------------------------------------ evidence
    def verify(self, n_samples=None, seed=None) -> CertificateReport:
        """Independent check: Gram matrices, and the contraction inequality at ``n_samples``
        states (default ``verify_samples``) drawn with ``seed`` (default ``seed_``)."""
        self._check_fitted()
        if seed is not None and (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, Integral)
                                 or not 0 <= seed <= MAX_SEED):
            raise InputError(f"seed must be None or an integer in [0, {MAX_SEED}], got {seed!r}")
        return check_model(self, self.verify_samples if n_samples is None else n_samples,
                           self.seed_ if seed is None else int(seed))

    def save(self, path, key=None) -> Path:
        """Write the model to ``path`` (JSON, atomically); with ``key`` (or $SOSDYN_MODEL_KEY)
        also an HMAC-SHA256 signature. See :func:`save_model`."""
        return save_model(self, path, key)

    @property
    def _vars(self) -> tuple:
        return tuple(f"z{i + 1}" for i in range(self.dim_))

    @property
    def n_iter_(self) -> int:
        return len(self.history_)


def resolve_seed(random_state) -> int:
    """The integer seed a fit uses: the integer itself, one drawn from a Generator/RandomState
    (advancing it, as sklearn does), or a fresh one for None."""
    if isinstance(random_state, np.random.RandomState):
        return int(random_state.randint(0, MAX_SEED, dtype=np.int64))
    if random_state is None or isinstance(random_state, np.random.Generator):
        return int(np.random.default_rng(random_state).integers(0, MAX_SEED))
    return int(random_state)


# ---------------------------------------------------------------------- model files
_STATE = ("dim_", "goal_", "scale_", "dt_", "units_", "n_components_", "gmr_cost_", "C_", "W_",
          "field_exps_", "metric_exps_", "mixture_", "certificate_", "history_", "metric_collapse_",
          "timings_")


def save_model(model, path, key=None) -> Path:
    """Write a fitted CDSP to ``path``: format, version, parameters, learned state, checksum and,
    with ``key`` (bytes or str; default $SOSDYN_MODEL_KEY), an HMAC-SHA256 signature. Atomic: a
    failing save leaves any previous file at ``path`` intact. The parameter ``random_state`` is
    recorded as the integer seed the fit used (``seed_``)."""
    model._check_fitted()
    m = model.mixture_
    state = {k: getattr(model, k) for k in _STATE if k != "mixture_"}
    state["mixture_"] = {"weights": m.weights, "means": m.means, "covariances": m.covariances}
    params = dict(model.get_params(), random_state=model.seed_)
    return write_model_file({"format": FORMAT, "version": VERSION, "params": params, "state": state},
                            path, key)


def load_model(path, key=None) -> CDSP:
    """Read a model written by :func:`save_model`: every field validated, certificate re-checked.

    With ``key`` (bytes or str; default $SOSDYN_MODEL_KEY) the file must carry a matching HMAC.
    The certificate is re-checked from the model's own coefficients (Gram matrices, and
    DEFAULT_SAMPLES sampled states with a fixed seed): the file's ``verify_samples`` and
    ``random_state`` do not make this check weaker. Every failure is a ModelFileError.
    """
    path = Path(path)
    content = read_model_file(path, key)
    try:
        model = _model_from_content(content)
    except ModelFileError as exc:
        text = str(exc).rstrip(".")
        raise ModelFileError(f"{path}: {text}." + ("" if "Try:" in text else f" {REFIT_HINT}")) from None
    try:
        report = model.verify(DEFAULT_SAMPLES, LOAD_SEED)
    except (SosdynError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        raise ModelFileError(f"{path}: its certificate cannot be re-checked from its coefficients "
                             f"({type(exc).__name__}: {exc}); refusing to load. {REFIT_HINT}") from None
    if not report.passed:
        raise ModelFileError(f"{path}: the stored certificate does not check out; refusing to load.\n"
                             f"{report}\n{REFIT_HINT}")
    model.verification_, model.certified_ = report, True
    return model


def _model_from_content(content: dict) -> CDSP:
    """A CDSP (not yet verified) from a file's content; ModelFileError naming the first bad field."""
    params = need(content, "params", "", dict)
    expected = set(CDSP().get_params())
    if set(params) != expected:
        missing, unknown = sorted(expected - set(params)), sorted(set(params) - expected)
        raise ModelFileError(f"malformed: params {'lacks ' + str(missing) if missing else ''}"
                             f"{' and ' if missing and unknown else ''}"
                             f"{'has unknown ' + str(unknown) if unknown else ''}")
    model = CDSP(**params)
    try:
        model._check_params()
    except InputError as exc:
        raise ModelFileError(f"invalid params: {exc}") from None
    model.seed_ = resolve_seed(model.random_state)
    st = need(content, "state", "", dict)
    n = integer(need(st, "dim_", "state"), "state.dim_", 1)
    K = integer(need(st, "n_components_", "state"), "state.n_components_", 1)
    if model.n_components != "bic" and K != model.n_components:
        raise ModelFileError(f"malformed: state.n_components_ = {K} but params.n_components = "
                             f"{model.n_components}")
    F, D = model.field_degree, model.metric_degree if model.metric == "learned" else 0
    fexps = _exponents(st, "field_exps_", n, math.comb(n + F, F) - 1, lambda: field_exponents(n, F))
    mexps = _exponents(st, "metric_exps_", n, math.comb(n + D, D), lambda: metric_exponents(n, D))
    model.dim_, model.n_components_, model.field_exps_, model.metric_exps_ = n, K, fexps, mexps
    model.goal_ = array(need(st, "goal_", "state"), "state.goal_", (n,))
    model.scale_ = positive(need(st, "scale_", "state"), "state.scale_")
    model.dt_ = positive(need(st, "dt_", "state"), "state.dt_")
    model.units_ = short_string(need(st, "units_", "state"), "state.units_")
    model.gmr_cost_ = float(array(need(st, "gmr_cost_", "state"), "state.gmr_cost_", ()))
    model.C_ = array(need(st, "C_", "state"), "state.C_", (K, n, len(fexps)))
    model.W_ = array(need(st, "W_", "state"), "state.W_", (n, n, len(mexps)))
    if not np.array_equal(model.W_, model.W_.transpose(1, 0, 2)):
        raise ModelFileError("malformed: state.W_ is not symmetric in its first two axes, so M(z) "
                             "would not be a symmetric matrix")
    model.mixture_ = _mixture(need(st, "mixture_", "state", dict), K, n)
    model.certificate_ = _certificate(need(st, "certificate_", "state", dict), K, 0.5 * model.eps)
    model.history_ = need(st, "history_", "state", list)
    if not all(isinstance(row, dict) for row in model.history_):
        raise ModelFileError("malformed: state.history_ must be a list of objects")
    model.timings_ = need(st, "timings_", "state", dict)
    model.metric_collapse_ = need(st, "metric_collapse_", "state")
    if not (model.metric_collapse_ is None or isinstance(model.metric_collapse_, dict)):
        raise ModelFileError("malformed: state.metric_collapse_ must be null or an object")
    unknown = sorted(set(st) - set(_STATE))
    if unknown:
        raise ModelFileError(f"malformed: state has unknown fields {unknown}")
    return model


def _exponents(st, name, n, count, expected):
    """The exponent rows of ``name``: ``count`` distinct rows, the library's monomial set."""
    exps = array(need(st, name, "state"), f"state.{name}", (count, n), dtype=int)
    if not np.array_equal(np.unique(exps, axis=0), np.unique(expected(), axis=0)) \
            or len(np.unique(exps, axis=0)) != count:
        raise ModelFileError(f"malformed: state.{name} are not the monomials the parameters imply "
                             f"({count} distinct exponent rows in {n} variables)")
    return exps


def _mixture(mx, K, n) -> PositionMixture:
    """Weights > 0 summing to 1, means (K, n), covariances (K, n, n) symmetric positive definite."""
    w = array(need(mx, "weights", "state.mixture_"), "state.mixture_.weights", (K,))
    means = array(need(mx, "means", "state.mixture_"), "state.mixture_.means", (K, n))
    cov = array(need(mx, "covariances", "state.mixture_"), "state.mixture_.covariances", (K, n, n))
    if not (w > 0).all() or abs(w.sum() - 1.0) > 1e-9:
        raise ModelFileError(f"malformed: state.mixture_.weights must be positive and sum to 1, got "
                             f"{np.array2string(w, precision=4)} (sum {w.sum():.12g})")
    for k in range(K):
        S = cov[k]
        if np.abs(S - S.T).max() > 1e-12 * max(1.0, np.abs(S).max()):
            raise ModelFileError(f"malformed: state.mixture_.covariances[{k}] is not symmetric")
        try:
            np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            raise ModelFileError(f"malformed: state.mixture_.covariances[{k}] is not positive definite "
                                 "(no Cholesky factor)") from None
    return PositionMixture(w, means, cov)


def _certificate(cert, K, eps) -> dict:
    """Status, eps (the fit's eps / 2) and K + 1 constraints of square, finite Gram matrices."""
    where = "state.certificate_"
    if not isinstance(need(cert, "status", where), str):
        raise ModelFileError(f"malformed: {where}.status must be a string")
    if not math.isclose(positive(need(cert, "eps", where), f"{where}.eps"), eps, rel_tol=1e-12):
        raise ModelFileError(f"malformed: {where}.eps = {cert['eps']!r}, but the parameters imply "
                             f"eps / 2 = {eps!r}")
    cons = need(cert, "constraints", where, list)
    if len(cons) != K + 1:
        raise ModelFileError(f"malformed: {where}.constraints has {len(cons)} entries; K + 1 = {K + 1} "
                             "(M - eps I, then -G_k for each component)")
    for i, c in enumerate(cons):
        w = f"{where}.constraints[{i}]"
        if not isinstance(need(c, "name", w), str):
            raise ModelFileError(f"malformed: {w}.name must be a string")
        vars = need(c, "vars", w, list)
        if not vars or not all(isinstance(v, str) for v in vars) or len(set(vars)) != len(vars):
            raise ModelFileError(f"malformed: {w}.vars must be distinct variable names")
        basis = need(c, "basis", w, list)
        array(basis, f"{w}.basis", (len(basis), len(vars)), dtype=int)
        array(need(c, "gram", w), f"{w}.gram", (len(basis), len(basis)))
    return cert

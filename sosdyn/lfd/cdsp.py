"""The CDSP estimator: contracting dynamical system primitives (Ravichandar et al.).

Model (eq. 2, goal-shifted and scaled, z = (x - x*)/s):  zdot = sum_k h_k(z) f_k(z),
f_k(0) = 0 (eq. 5). Guarantee (eq. 4/9, SOS form eq. 14-19): for every k,
-G_k(z) = -(J_k^T M + M J_k + dM[f_k] + gamma M) is an SOS matrix and M - eps I is an SOS
matrix, so the virtual system ydot = sum_k h_k(x) f_k(y) contracts in the metric M at rate
gamma whatever the weights h_k, and every trajectory converges to x* (Theorem 1).

The estimator holds parameters and learned state; the mathematics is in functions on arrays:
:mod:`.learner` (the stages), :mod:`.steps` (the convex steps), :mod:`.contraction` (G_k and M),
:mod:`.certificate` (certify and check), :mod:`.refine` (the mixture), :mod:`.gmm` (EM).

Model files (:func:`save_model`, :func:`load_model`; the file in :mod:`.model_io`, its state
in :mod:`.model_state`): loading validates every field and re-checks the certificate from the
model's own coefficients with the library's DEFAULT_SAMPLES states. The certificate lives in
z-coordinates and does not involve the weights h_k, so an edited goal, scale or mixture leaves
it valid while changing the motion: only the checksum (accidents) or the keyed signature
(deliberate edits) detect such an edit.
"""
from __future__ import annotations

import inspect
import time
import warnings
from numbers import Integral
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from ..errors import InputError, ModelFileError, NotCertifiedError, NotFittedError, SosdynError
from .certificate import (DEFAULT_SAMPLES, CertificateReport, certify, check_certificate, collapse_diagnostic,
                          extract_certificate)
from .contraction import eval_fields, field_exponents, metric_exponents
from .data import check_demonstrations
from .evaluator import StatePredictor
from .gmm import MIN_SAMPLES_PER_COMPONENT, PositionMixture, fit_joint_gmm, gmr_cost
from .learner import History, Settings, learn, subsample
from .model_io import FORMAT, REFIT_HINT, VERSION, read_model_file, write_model_file
from .model_state import STATE_FIELDS, check_param_names, need, state_record, validate_state
from .params import LEGACY_PARAMS, MAX_SEED, PARAMS, check_params, check_solver, preset_params, resolve_seed
from .rollout import rollout as integrate

LOAD_SEED = 0                   # the states of the sampled check when loading a file
METRIC_PROX = 1e-2              # default proximal weight of the metric step (well-posed alternation)


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
    solver_method : {"alternating", "ica"}   plain alternation, or the inner convex approximation
                                 (ignored with metric="identity": one dynamics step).
    max_iter, tol                alternation / ICA iterations and relative cost tolerance.
    eps, margin                  M >= eps I; the trained fields satisfy -G_k >= margin I.
    metric_prox : float >= 0     proximal weight rho of the metric step (maximise t - rho |w - w0|^2,
                                 unique maximiser); 0 = the paper's plain max-margin step.
    refine_gmm : bool            also optimise the GMM's position means/covariances (paper's theta_G).
    max_samples : int or None    subsample the data to at most this many points (EM and fit).
    random_state : None, int in [0, 2^32), np.random.Generator or RandomState
                                 seed of EM and of the verification samples; the integer seed
                                 actually used is ``seed_`` (and is what a saved file records).
    verify_samples : int         states of the sampled certificate check, in [100, 10^6].
    allow_uncertified : bool     return a model whose check failed (flagged) instead of raising.
    progress : callable or None  called with each history row while fitting.

    Defaults: ``CDSP()`` is the "ica" preset with K = 8 Gaussians. On the ds-opt LASA protocol,
    of the single configurations tried, K = 8 and K = 10 had the lowest 26-shape mean DTWD of
    reproductions of the training demonstrations (1511 and 1508 mm, a tie; K = 8 is faster);
    its test mean is 1919 mm, against 2880 for "paper".
    Presets (``CDSP.preset(name, **overrides)``, :data:`~sosdyn.lfd.params.PRESETS`):
    ``"paper"`` is the paper's alternating formulation, the former default (the reproduction
    ``python -m problems run`` sets its parameters explicitly, with ``metric_prox=0``);
    ``"ica"`` the same linear model by the inner convex approximation, K = 6; ``"cubic"`` cubic
    sub-systems and a degree-2 metric. A choice per data set among configurations from the
    training demonstrations alone: :func:`sosdyn.evaluation.dsopt.select_fit` (the
    "CDSP selected" variants of ``make lasa-dsopt``).

    Numbers may be Python or numpy scalars (np.float32, np.int64); booleans are not numbers
    here. Every parameter is checked before any optimisation (InputError saying what to try).

    Learned attributes end in ``_``: ``goal_``, ``scale_``, ``mixture_``, ``C_`` (K, n, m),
    ``W_`` (n, n, p), ``history_``, ``certificate_``, ``verification_``, ``metric_collapse_``.
    """

    name = "CDSP"

    def __init__(self, n_components=8, metric_degree=0, field_degree=1, gamma=0.1, metric="learned",
                 solver="CLARABEL", solver_method="ica", max_iter=20, tol=1e-4, eps=1e-3,
                 margin=1e-4, metric_prox=METRIC_PROX, refine_gmm=False, max_samples=3000, random_state=0,
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
        self.metric_prox = metric_prox
        self.refine_gmm = refine_gmm
        self.max_samples = max_samples
        self.random_state = random_state
        self.verify_samples = verify_samples
        self.allow_uncertified = allow_uncertified
        self.progress = progress

    @classmethod
    def preset(cls, name: str, **overrides) -> CDSP:
        """An unfitted CDSP with the parameters of preset ``name`` (class docstring), then ``overrides``."""
        return cls(**{**preset_params(name), **overrides})

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in PARAMS}

    def check_params(self) -> None:
        """Every parameter's type and range, and the solver (InputError saying what to try)."""
        check_params(dict(self.get_params(), progress=self.progress), DEFAULTS)
        check_solver(self.solver)

    # ------------------------------------------------------------------ fitting
    def fit(self, demos):
        """Learn from Demonstrations (validated first); returns self.

        BLAS runs single-threaded inside: every matrix here is small, and a multi-threaded
        OpenBLAS spin-waits on small problems (measured 10-100x slower on 2 loaded cores).
        """
        with threadpool_limits(limits=1, user_api="blas"):
            return self._fit(demos)

    def _fit(self, demos):
        t_start = time.perf_counter()
        self.check_params()
        demos = check_demonstrations(demos)
        K = 1 if self.n_components == "bic" else int(self.n_components)
        X, Xdot, subsampled = subsample(*demos.stacked(), self.max_samples)
        if X.shape[0] < MIN_SAMPLES_PER_COMPONENT * K:
            raise InputError(f"{X.shape[0]} samples{' (after max_samples)' if subsampled else ''} are "
                             f"too few for {K} Gaussians; use fewer components, more demonstrations"
                             f"{' or a larger max_samples' if subsampled else ''}")
        self.seed_ = resolve_seed(self.random_state)
        self.dim_, self.goal_ = demos.dim, np.asarray(demos.goal, dtype=float)
        self.scale_ = float(np.abs(X - self.goal_).max()) or 1.0
        self.dt_ = float(np.median(np.concatenate([np.diff(d.t) for d in demos])))
        self.units_ = demos.units
        Z, Zdot = (X - self.goal_) / self.scale_, Xdot / self.scale_
        history = History(self.progress)
        self.history_, self.timings_ = history.rows, {}
        settings = Settings.from_params(self.get_params())

        t0 = time.perf_counter()
        gmm, bic = fit_joint_gmm(Z, Zdot, self.n_components, self.seed_)
        if bic is not None:
            self.bic_ = bic
        self.n_components_ = gmm.n_components
        self.mixture_ = PositionMixture.from_joint(gmm, self.dim_)
        self.timings_["em_s"] = time.perf_counter() - t0
        self.field_exps_ = field_exponents(self.dim_, self.field_degree)
        self.metric_exps_ = metric_exponents(self.dim_, settings.learned_metric_degree)
        self.gmr_cost_ = gmr_cost(gmm, Z, Zdot)

        t0 = time.perf_counter()
        self.C_, self.W_, self.mixture_ = learn(Z, Zdot, self.mixture_, settings, history)
        self.timings_["learn_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        sol = certify(self.C_, self.field_exps_, self.W_, self.metric_exps_, self.gamma, 0.5 * self.eps,
                      self.solver)
        self.certificate_ = extract_certificate(sol, 0.5 * self.eps)
        self.timings_["certify_s"] = time.perf_counter() - t0
        self.metric_collapse_ = collapse_diagnostic(self.C_, self.field_exps_, self.W_, self.metric_exps_,
                                                    self.gamma, self.seed_)
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
        return self

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

    def predictor(self) -> StatePredictor:
        """A fast one-state evaluator, ``predictor(x) -> xdot`` (see :mod:`.evaluator`)."""
        self._check_fitted()
        return StatePredictor(self.goal_, self.scale_, self.mixture_, self.C_, self.field_exps_)

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
        return check_certificate(self.C_, self.field_exps_, self.W_, self.metric_exps_, self.gamma,
                                 self.certificate_, self.verify_samples if n_samples is None else n_samples,
                                 self.seed_ if seed is None else int(seed))

    def save(self, path, key=None) -> Path:
        """Write the model to ``path`` (JSON, atomically); with ``key`` (or $SOSDYN_MODEL_KEY)
        also an HMAC-SHA256 signature. See :func:`save_model`."""
        return save_model(self, path, key)

    @property
    def n_iter_(self) -> int:
        return len(self.history_)


DEFAULTS = {name: p.default for name, p in inspect.signature(CDSP).parameters.items()}


# ---------------------------------------------------------------------- model files
def save_model(model: CDSP, path, key=None) -> Path:
    """Write a fitted CDSP to ``path``: format, version, parameters, learned state, checksum and,
    with ``key`` (bytes or str; default $SOSDYN_MODEL_KEY), an HMAC-SHA256 signature. Atomic: a
    failing save leaves any previous file at ``path`` intact. The parameter ``random_state`` is
    recorded as the integer seed the fit used (``seed_``)."""
    model._check_fitted()
    state = state_record({k: getattr(model, k) for k in STATE_FIELDS})
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
        model = model_from_content(content)
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


def model_from_content(content: dict) -> CDSP:
    """A CDSP (not yet verified) from a file's content; ModelFileError naming the first bad field."""
    params = dict(LEGACY_PARAMS, **need(content, "params", "", dict))   # files older than a parameter
    check_param_names(params, PARAMS)
    model = CDSP(**params)
    try:
        check_params(params, DEFAULTS)
    except InputError as exc:
        raise ModelFileError(f"invalid params: {exc}") from None
    model.seed_ = resolve_seed(model.random_state)
    metric_degree = Settings.from_params(params).learned_metric_degree
    state = validate_state(need(content, "state", "", dict), model.n_components, model.field_degree,
                           metric_degree, 0.5 * model.eps)
    for name, value in state.items():
        setattr(model, name, value)
    return model

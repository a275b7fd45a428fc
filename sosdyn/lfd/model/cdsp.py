"""The CDSP estimator: contracting dynamical system primitives (Ravichandar et al.).

Model (eq. 2, goal-shifted and scaled, z = (x - x*)/s):  zdot = sum_k h_k(z) f_k(z),
f_k(0) = 0 (eq. 5). Guarantee (eq. 4/9, SOS form eq. 14-19): for every k,
-G_k(z) = -(J_k^T M + M J_k + dM[f_k] + gamma M) is an SOS matrix and M - eps I is an SOS
matrix, so the virtual system ydot = sum_k h_k(x) f_k(y) contracts in the metric M at rate
gamma whatever the weights h_k, and every trajectory converges to x* (Theorem 1). With a warp
(parameter ``warp``, :mod:`.warp`) the same holds in u = phi(z) and carries over to z (class docstring).

The estimator holds parameters and learned state; the mathematics is in functions on arrays:
:mod:`.learner` (the stages), :mod:`.steps` (the convex steps), :mod:`.contraction` (G_k and M),
:mod:`.certificate` (certify and check), :mod:`.refine` (the mixture), :mod:`.gmm` (EM),
:mod:`.warp` (the pre-warp), :mod:`.rounds` (fits made of several fits).

Model files (:meth:`CDSP.save`, :func:`~.model_files.load_model`; the file in :mod:`.model_io`, its
state in :mod:`.model_state`): loading validates every field and re-checks the certificate from the
model's own coefficients with the library's DEFAULT_SAMPLES states. The certificate lives in
z-coordinates and does not involve the weights h_k, so an edited goal, scale or mixture leaves
it valid while changing the motion: only the checksum (accidents) or the keyed signature
(deliberate edits) detect such an edit.
"""
from __future__ import annotations

import inspect
import time
import warnings
from dataclasses import replace
from numbers import Integral
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from sosdyn.errors import InputError, NotCertifiedError, NotFittedError
from ..fit.certificate import (
    DEFAULT_SAMPLES,
    CertificateReport,
    certify,
    check_certificate,
    collapse_diagnostic,
    extract_certificate,
)
from ..fit.contraction import eval_fields, field_exponents, metric_exponents
from ..fit.corrective import MIN_DIST, ROUNDS, TAU
from ..data.demonstrations import check_demonstrations, sample_step
from ..data.poses import PoseDemonstrations
from ..runtime.predictor import StatePredictor
from ..runtime.states import as_state, as_states, check_max_speed, limit_speed
from ..fit.gmm import MIN_SAMPLES_PER_COMPONENT, PositionMixture, fit_joint_gmm, gmr_cost
from ..fit.learner import History, Settings, learn, reuse_steps, subsample
from .fileformat import FORMAT, VERSION, write_model_file
from .state import STATE_FIELDS, state_record
from ..fit.params import (
    MAX_SEED,
    PARAMS,
    check_params,
    check_solver,
    preset_params,
    resolve_seed,
    warp_settings,
)
from ..rollout import rollout as integrate
from ..rollout.quality import reproduction_table
from ..fit.rounds import corrective_fits, warp_choice
from ..fit.warp import AUTO_WARPS, check_warp, fit_warp, jacobian, pulled_back

METRIC_PROX = 1e-2              # default proximal weight of the metric step (well-posed alternation)


class CDSP:
    """Learn a partially contracting dynamical system from demonstrations.

    **Parameters**

    - ``n_components`` (int or "bic"): K, Gaussians of the GMM (paper: 6/7/6/6); "bic" picks K
      in 1..10 by the Bayesian information criterion of EM fits.
    - ``metric_degree`` (int): degree of M(z) (0 = constant metric; even).
    - ``field_degree`` (int): degree of the sub-systems f_k (1 = the paper's A_k x + b_k; odd).
    - ``gamma`` (float): contraction rate (1/s, in the data's time units).
    - ``metric`` ("learned" or "identity"): "identity" fixes M = I (SEDS-like quadratic Lyapunov).
    - ``solver`` (str): conic solver ("CLARABEL"; "SCS" or another solver installed in cvxpy).
    - ``solver_method`` ("alternating" or "ica"): plain alternation, or the inner convex
      approximation (ignored with metric="identity": one dynamics step).
    - ``max_iter``, ``tol``: alternation / ICA iterations and relative cost tolerance.
    - ``eps``, ``margin``: M >= eps I; the trained fields satisfy -G_k >= margin I.
    - ``metric_prox`` (float >= 0): proximal weight rho of the metric step (maximise
      t - rho |w - w0|^2, unique maximiser); 0 = the paper's plain max-margin step.
    - ``refine_gmm`` (bool): also optimise the GMM's position means/covariances (paper's theta_G).
    - ``max_samples`` (int or None): subsample the data to at most this many points (EM and fit).
    - ``random_state`` (None, int in [0, 2^32), np.random.Generator or RandomState): seed of EM
      and of the verification samples; the integer seed actually used is ``seed_`` (and is what
      a saved file records).
    - ``verify_samples`` (int): states of the sampled certificate check, in [100, 10^6].
    - ``allow_uncertified`` (bool): return a model whose check failed (flagged) instead of raising.
    - ``progress`` (callable or None): called with each history row while fitting.
    - ``corrective_rounds`` (int): refits on corrective data from the model's own training
      rollouts (``sosdyn.lfd.fit.corrective``, ``corrective_fits``), 0..10; 0 = none.
    - ``corrective_tau``, ``corrective_min_dist``: the corrective labels' time constant (s) and the
      distance (x the data's scale) below which a rollout state gets no label.
    - ``warp`` ("auto", "none" or dict): fit in warped coordinates u = phi(z), phi a
      diffeomorphism of Gaussian bumps fixing the goal (``sosdyn.lfd.fit.warp``); a dict (keys of
      ``WARP_DEFAULTS``) is one fixed warp; "auto" fits no warp and each ``AUTO_WARPS`` candidate
      and keeps the one whose rollouts from the training demos' starts deviate least from them.

    Warp (z = (x - x*)/s): the core f is fitted on (phi(z_i), J_phi(z_i) zdot_i) and certified in
    u as always; the model is zdot = J_phi(z)^{-1} f(phi(z)). Since du = J_phi dz, the x-system is
    partially contracting at rate gamma in the metric J_phi^T M J_phi (every trajectory converges to
    the goal; nearby ones need not approach each other: docs/theory.md), uniformly definite because every bump's
    Lipschitz number l_j < 1 (prod (1 - l_j)^2 M <= J^T M J <= prod (1 + l_j)^2 M); phi(0) = 0 keeps
    the goal, and goal changes and rescaling work as without a warp. ``verify`` adds the warp's
    check (every l_j < 1 recomputed, sampled sigma_min(J_phi) >= prod (1 - l_j)) to the report.

    Defaults: ``CDSP()`` is the "ica" preset with K = 8 Gaussians and warp="auto", no corrective
    rounds. On the ds-opt LASA protocol (26 shapes, random_state 0): test mean DTWD 796 mm
    (median 764, worst 4.1x copying the nearest demo), ~4 s per shape for the three fits (no
    warp: 1919; 3 corrective rounds instead of the warp: 1438; "paper": 2880); corrective rounds
    inside the warps did not help (1257 vs 1258). K = 8 and K = 10 had the lowest training means
    of the single plain configurations (1511, 1508 mm; K = 8 is faster).
    Presets (``CDSP.preset(name, **overrides)``, :data:`~sosdyn.lfd.fit.params.PRESETS`) are one plain
    fit each (warp="none", corrective_rounds=0): ``"paper"`` the paper's alternating formulation
    (the reproduction ``python -m problems run`` sets its parameters explicitly); ``"ica"`` the
    same linear model by the inner convex approximation, K = 6; ``"cubic"`` cubic sub-systems and
    a degree-2 metric. A choice per data set among configurations from the training demonstrations
    alone: :func:`sosdyn.evaluation.dsopt.select_fit` (the "CDSP selected" variants).

    Numbers may be Python or numpy scalars (np.float32, np.int64); booleans are not numbers
    here. Every parameter is checked before any optimisation (InputError saying what to try).

    Learned attributes end in ``_``: ``goal_``, ``scale_``, ``mixture_``, ``C_`` (K, n, m),
    ``W_`` (n, n, p), ``warp_`` (None or the bumps' z-unit centers, vectors, sigmas), ``history_``,
    ``certificate_``, ``verification_``, ``metric_collapse_``; set by ``fit`` only (not in a
    model file): ``warp_scores_`` (each "auto" candidate's training deviation, data units),
    ``corrective_round_``, ``corrective_scores_``, ``corrective_pairs_`` (per round).
    """

    name = "CDSP"

    def __init__(self, n_components=8, metric_degree=0, field_degree=1, gamma=0.1, metric="learned",
                 solver="CLARABEL", solver_method="ica", max_iter=20, tol=1e-4, eps=1e-3,
                 margin=1e-4, metric_prox=METRIC_PROX, refine_gmm=False, max_samples=3000, random_state=0,
                 verify_samples=DEFAULT_SAMPLES, allow_uncertified=False, progress=None,
                 corrective_rounds=ROUNDS, corrective_tau=TAU, corrective_min_dist=MIN_DIST, warp="auto"):
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
        self.corrective_rounds = corrective_rounds
        self.corrective_tau = corrective_tau
        self.corrective_min_dist = corrective_min_dist
        self.warp = warp

    @classmethod
    def preset(cls, name: str, **overrides) -> CDSP:
        """An unfitted CDSP with the parameters of preset ``name`` (class docstring), then ``overrides``."""
        return cls(**{**preset_params(name), **overrides})

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in PARAMS}

    def __repr__(self) -> str:
        """``CDSP(n_components=6, warp='none')``: the parameters that differ from the defaults;
        fitted, also ``K``, ``n``, the goal and whether the certificate passed its check."""
        changed = [f"{k}={v!r}" for k, v in self.get_params().items() if not (v is DEFAULTS[k] or v == DEFAULTS[k])]
        if hasattr(self, "C_"):
            warp = "none" if self.warp_ is None else f"{len(self.warp_['sigmas'])} bumps"
            changed.append(f"fitted: K={self.C_.shape[0]}, n={self.dim_}, goal="
                           f"{np.array2string(self.goal_, precision=4, separator=', ')}, warp={warp}, "
                           f"certified={bool(self.verification_.passed)}")
        return f"CDSP({', '.join(changed)})"

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
        with threadpool_limits(limits=1, user_api="blas"), reuse_steps():    # one compile per step structure
            return self._fit(demos)

    def _fit(self, demos):
        t_start = time.perf_counter()
        self.check_params()
        if isinstance(demos, PoseDemonstrations):
            raise InputError("these are pose demonstrations (position + orientation). Try: sosdyn.PoseCDSP(**params)"
                             ".fit(demos), the certified CDSP of the 6-D chart state (same parameters).")
        demos = check_demonstrations(demos)
        if self.warp == "auto":
            return self._fit_auto(demos, t_start)
        settings = warp_settings(self.warp)
        self.warp_scores_ = {}
        return self._fit_core(demos, None if settings is None else
                              fit_warp([(d.t, d.pos) for d in demos], demos.goal, settings), t_start)

    def _fit_auto(self, demos, t_start):
        """warp="auto": :func:`~.rounds.warp_choice` among no warp and AUTO_WARPS (same seed); a
        candidate whose fitted bumps equal an earlier one's (the greedy fit stopped early) reuses its fit."""
        seed = resolve_seed(self.random_state)
        fitted = {}

        def fit_candidate(name, settings):
            tagged = None if self.progress is None else (lambda row: self.progress(dict(row, warp=name)))
            maps = None if settings is None else fit_warp([(d.t, d.pos) for d in demos], demos.goal, settings)
            key = None if maps is None else b"".join(np.ascontiguousarray(a).tobytes() for a in maps)
            if key not in fitted:
                fitted[key] = CDSP(**dict(self.get_params(), random_state=seed, progress=tagged))._fit_core(
                    demos, maps, time.perf_counter())
            return fitted[key]

        kept, self.warp_scores_ = warp_choice(fit_candidate, {"none": None, **AUTO_WARPS}, demos)
        self.__dict__.update({k: v for k, v in vars(kept).items() if k.endswith("_") and k != "warp_scores_"})
        self.timings_ = dict(kept.timings_, total_s=time.perf_counter() - t_start)
        return self

    def _fit_core(self, demos, maps, t_start):
        """One fit, plain or with corrective rounds (:func:`~.rounds.corrective_fits`; the kept
        round's learned state becomes this model's, ``history_`` holds every round's rows), through
        the warp ``maps`` (data units, or None)."""
        if self.corrective_rounds == 0:
            self.corrective_round_, self.corrective_scores_, self.corrective_pairs_ = 0, [], []
            return self._fit_plain(demos, t_start, maps)
        seed = resolve_seed(self.random_state)

        def fit_round(r, data):
            tagged = None if self.progress is None else (lambda row: self.progress(dict(row, round=r)))
            return CDSP(**dict(self.get_params(), random_state=seed, corrective_rounds=0, progress=tagged)
                        )._fit_plain(data, time.perf_counter(), maps)

        self.corrective_round_, kept, self.corrective_scores_, self.corrective_pairs_, history = corrective_fits(
            fit_round, demos, self.corrective_rounds, self.corrective_tau, self.corrective_min_dist)
        self.__dict__.update({k: v for k, v in vars(kept).items() if k.endswith("_")
                              and not k.startswith("corrective_")})
        self.history_, self.dt_ = history, sample_step(demos)
        self.timings_ = dict(kept.timings_, total_s=time.perf_counter() - t_start)
        return self

    def _fit_plain(self, demos, t_start, maps=None):
        """One fit of the mixture, the fields and the metric, then the certificate and its check;
        with ``maps`` (a warp in data units, :func:`~.warp.fit_warp`) in u = phi(z) on (phi(z_i),
        J_phi(z_i) zdot_i), the warp stored in z-units as ``warp_`` (None if it has no bump)."""
        K = 1 if self.n_components == "bic" else int(self.n_components)
        X, Xdot, subsampled = subsample(*demos.stacked(), self.max_samples)
        if X.shape[0] < MIN_SAMPLES_PER_COMPONENT * K:
            raise InputError(f"{X.shape[0]} samples{' (after max_samples)' if subsampled else ''} are "
                             f"too few for {K} Gaussians; use fewer components, more demonstrations"
                             f"{' or a larger max_samples' if subsampled else ''}")
        self.seed_ = resolve_seed(self.random_state)
        self.dim_, self.goal_ = demos.dim, np.asarray(demos.goal, dtype=float)
        self.scale_ = float(np.abs(X - self.goal_).max()) or 1.0
        self.dt_ = sample_step(demos)
        self.units_ = demos.units
        Z, Zdot = (X - self.goal_) / self.scale_, Xdot / self.scale_
        self.warp_ = None if maps is None or not len(maps[2]) else {
            "centers": (maps[0] - self.goal_) / self.scale_, "vectors": maps[1] / self.scale_,
            "sigmas": maps[2] / self.scale_}
        if self.warp_ is not None:
            Z, J = jacobian(Z, *self._maps(), np.zeros(self.dim_))
            Zdot = np.einsum("tij,tj->ti", J, Zdot)
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

    def _maps(self):
        return self.warp_["centers"], self.warp_["vectors"], self.warp_["sigmas"]

    def _core(self, U):
        """udot = sum_k h_k(u) f_k(u) at the rows of U (the certified system)."""
        return np.einsum("tk,tki->ti", self.mixture_.responsibilities(U), eval_fields(self.C_, self.field_exps_, U))

    def field(self, X, goal):
        """xdot at the rows of X for the goal ``goal`` (the field translated to the goal):
        s f(z), or through the warp s J_phi(z)^{-1} f(phi(z)), z = (x - goal) / s."""
        Z = (X - goal) / self.scale_
        return (self._core(Z) if self.warp_ is None else pulled_back(Z, self._maps(), self._core)) * self.scale_

    def predict(self, X):
        """Velocities (m, n) at the states X (m, n), in the data's units."""
        self._check_fitted()
        X = as_states(X, self.dim_)
        with np.errstate(over="ignore", invalid="ignore"):
            V = self.field(X, self.goal_)
        bad = np.flatnonzero(~np.isfinite(V).all(axis=1))
        if bad.size:
            raise InputError(f"X row {bad[0]} = {X[bad[0]]} is so far from the data (scale {self.scale_:.3g}) "
                             f"that the degree-{self.field_degree} field overflows float. Try: states "
                             "within a few orders of magnitude of the demonstrations.")
        return V

    def predictor(self, max_speed=None) -> StatePredictor:
        """A fast one-state evaluator, ``step(x, goal=None) -> xdot`` (:mod:`~sosdyn.lfd.runtime.predictor`):
        ``goal`` moves the goal at run time; ``max_speed`` (data units / s) scales xdot by
        min(1, max_speed / |xdot|) (same paths and goal, ``docs/theory.md``)."""
        self._check_fitted()
        return StatePredictor(self.goal_, self.scale_, self.mixture_, self.C_, self.field_exps_,
                              None if self.warp_ is None else self._maps(), max_speed)

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None):
        """Integrate from x0; pushes [(t, dx)] and goal changes [(t, g)] as in sosdyn.lfd.rollout.

        ``dt`` None means the model's ``dt_``; duration and dt are checked by the integrator, whose
        absolute tolerance is relative to the data's scale ``scale_`` (the same relative accuracy
        in any units) and whose work is bounded (``max_rollout_calls``, ``max_rollout_seconds``).
        ``max_speed``: the field scaled by min(1, max_speed / |xdot|), as ``predictor(max_speed=...)``."""
        self._check_fitted()
        x0 = as_state(x0, self.dim_, "x0")
        goal = self.goal_ if goal is None else as_state(goal, self.dim_, "goal")
        max_speed = check_max_speed(max_speed)
        field = self.field if max_speed is None else (lambda X, g: limit_speed(self.field(X, g), max_speed))
        return integrate(field, x0, duration=duration, dt=self.dt_ if dt is None else dt, goal=goal,
                         perturbations=perturbations, goal_changes=goal_changes, scale=self.scale_)

    def score(self, demos) -> list[dict]:
        """Per demonstration, its reproduction from its first sample (step ``dt_``): deviation
        (mean / max, data units), arrival time, final error, at goal (columns and rules:
        :func:`~sosdyn.lfd.rollout.quality.reproduction_table`)."""
        self._check_fitted()
        demos = check_demonstrations(demos, goal_tol=np.inf)       # another dimension: predict's InputError
        return reproduction_table(self.predict, demos, self.goal_, self.dt_)

    # ------------------------------------------------------------------ evidence
    def verify(self, n_samples=None, seed=None) -> CertificateReport:
        """Independent check: Gram matrices, and the contraction inequality at ``n_samples``
        states (default ``verify_samples``) drawn with ``seed`` (default ``seed_``)."""
        self._check_fitted()
        if seed is not None and (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, Integral)
                                 or not 0 <= seed <= MAX_SEED):
            raise InputError(f"seed must be None or an integer in [0, {MAX_SEED}], got {seed!r}")
        n_samples = self.verify_samples if n_samples is None else n_samples
        seed = self.seed_ if seed is None else int(seed)
        report = check_certificate(self.C_, self.field_exps_, self.W_, self.metric_exps_, self.gamma,
                                   self.certificate_, n_samples, seed)
        if self.warp_ is None:
            return report
        warp = check_warp(self._maps(), n_samples, seed)
        return replace(report, warp=warp, passed=report.passed and warp["passed"])

    def save(self, path, key=None) -> Path:
        """Write the model to ``path`` (JSON, atomically): format, version, parameters, learned state,
        checksum and, with ``key`` (bytes or str; default $SOSDYN_MODEL_KEY), an HMAC-SHA256 signature.
        A failing save leaves any previous file intact. ``random_state`` is recorded as ``seed_``."""
        self._check_fitted()
        state = state_record({k: getattr(self, k) for k in STATE_FIELDS})
        params = dict(self.get_params(), random_state=self.seed_)
        return write_model_file({"format": FORMAT, "version": VERSION, "params": params, "state": state},
                                path, key)

    @property
    def n_iter_(self) -> int:
        return len(self.history_)


DEFAULTS = {name: p.default for name, p in inspect.signature(CDSP).parameters.items()}


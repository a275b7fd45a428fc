"""The CDSP estimator: contracting dynamical system primitives (Ravichandar et al.).

Model (eq. 2, goal-shifted and scaled, z = (x - x*)/s):  zdot = sum_k h_k(z) f_k(z),
f_k(0) = 0 (eq. 5). Guarantee (eq. 4/9, SOS form eq. 14-19): for every k,
-G_k(z) = -(J_k^T M + M J_k + dM[f_k] + gamma M) is an SOS matrix and M - eps I is an SOS
matrix, so the virtual system ydot = sum_k h_k(x) f_k(y) contracts in the metric M at rate
gamma whatever the weights h_k, and every trajectory converges to x* (Theorem 1). With a warp
(parameter ``warp``, :mod:`.warp`) the same holds in u = phi(z) and carries over to z (class docstring).

The estimator holds parameters and learned state; the mathematics is in functions on arrays.
``fit`` calls :func:`sosdyn.lfd.fit.pipeline.fit` once, the whole fit path read top-down
(demonstrations -> warp candidates -> core fits -> certificate and check -> choice), which calls
:mod:`.learner` (the stages), :mod:`.steps` (the convex steps), :mod:`.contraction` (G_k and M),
:mod:`.certificate` (certify and check), :mod:`.refine` (the mixture), :mod:`.gmm` (EM),
:mod:`.warp` (the pre-warp), :mod:`.rounds` (fits made of several fits).

CDSP is the first-order family of the model interface (:mod:`.base`). Model files
(:meth:`~.base.MotionModel.save`, :func:`~.files.load_model`; the file in :mod:`.fileformat`, its
content in :mod:`.content`): loading validates every field and re-checks the certificate from the
model's own coefficients with the library's DEFAULT_SAMPLES states. The certificate lives in
z-coordinates and does not involve the weights h_k, so an edited goal, scale or mixture leaves
it valid while changing the motion: only the checksum (accidents) or the keyed signature
(deliberate edits) detect such an edit.
"""
from __future__ import annotations

import inspect
import time
from numbers import Integral

import numpy as np
from threadpoolctl import threadpool_limits

from sosdyn.errors import InputError, ModelFileError, NotFittedError
from ..fit.certificate import DEFAULT_SAMPLES, CertificateReport
from ..fit.corrective import MIN_DIST, ROUNDS, TAU
from ..fit.floor import describe
from ..data.demonstrations import check_demonstrations
from ..data.pose import PoseDemonstrations
from ..fit.learner import Settings, capped, reuse_steps
from ..fit.params import LEGACY_PARAMS, MAX_SEED, PARAMS, check_params, check_solver, preset_params, resolve_seed
from ..fit.composite import maps_of, twist_of
from ..fit.pipeline import check_fit, field_at
from ..fit.pipeline import fit as fit_path
from ..rollout import rollout as integrate
from ..rollout.quality import HORIZON, reproduction_table
from ..runtime.export_cpp import to_cpp
from ..runtime.export_python import to_python
from ..runtime.predictor import StatePredictor
from ..runtime.states import as_state, as_states, check_max_speed, limit_speed
from .base import Layout, MotionModel, Reproductions
from .content import STATE_FIELDS, check_param_names, need, state_record, validate_state
from .fileformat import FORMAT, VERSION
from .reach import reach_box

METRIC_PROX = 1e-2              # default proximal weight of the metric step (well-posed alternation)


class CDSP(MotionModel):
    """Learn a partially contracting dynamical system from demonstrations: the first-order family of
    the model interface (:class:`~.base.MotionModel`).

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
    - ``gating`` ("smooth", "tempered" or "posterior"): the weights h_k. "posterior": the GMM's
      posterior. "tempered" divides the quadratic forms by tau = max(1, min_k d_k^2 / c) (c =
      max(chi^2_n(0.999), the training points' largest min_k d_k^2)), so the weights are the
      posterior, bit for bit, at every training point and turn smoothly off the data instead of
      switching between thin Gaussians: the 7-D reproductions' kinks (``sosdyn.lfd.fit.gmm``;
      docs/findings.md). "smooth" (the default) keeps those weights up to tau = 3 and beyond fades
      them to the mixing weights pi (one linear field far off the data): smooth joint motions from
      starts off the demonstrations. The fit is the same for all three; the certificate holds for
      every gating.
    - ``speed_floor`` ("auto", "none" or a rate kappa > 0, 1/s): the field times sigma(x) =
      min(10, max(1, kappa |x - x*| / |f(x)|)), a time change (same paths; the certificate holds at
      rate >= gamma, ``sosdyn.lfd.fit.floor``); "auto" uses the least kappa (none, or a quantile of the
      training samples' relative speeds |xdot| / |x - x*|) with which the reproductions of the training
      demonstrations reach the goal within 1.5x their duration: where demonstrations go in and out the
      averaged field crawls (16 of the 63 real pourings did not arrive in 2x their duration).

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
    fit each (warp="none", corrective_rounds=0, speed_floor="none"): ``"paper"`` the paper's alternating
    formulation (the reproduction ``python -m problems run`` sets its parameters explicitly); ``"ica"`` the
    same linear model by the inner convex approximation, K = 6; ``"cubic"`` cubic sub-systems and
    a degree-2 metric. A choice per data set among configurations from the training demonstrations
    alone: :func:`sosdyn.evaluation.dsopt.select_fit` (the "CDSP selected" variants).

    Numbers may be Python or numpy scalars (np.float32, np.int64); booleans are not numbers
    here. Every parameter is checked before any optimisation (InputError saying what to try).

    Learned attributes end in ``_``: ``goal_``, ``scale_``, ``units_``, ``columns_`` (the position
    columns' names, None: unnamed), ``mixture_``, ``C_`` (K, n, m),
    ``W_`` (n, n, p), ``warp_`` (None or the bumps' z-unit centers, vectors, sigmas), ``history_``,
    ``certificate_``, ``verification_``, ``metric_collapse_``; set by ``fit`` only (not in a
    model file): ``warp_scores_`` (each "auto" candidate's training deviation, data units),
    ``corrective_round_``, ``corrective_scores_``, ``corrective_pairs_`` (per round).
    """

    name = "CDSP"
    file_format, file_version = FORMAT, VERSION

    def __init__(self, n_components=8, metric_degree=0, field_degree=1, gamma=0.1, metric="learned",
                 solver="CLARABEL", solver_method="ica", max_iter=20, tol=1e-4, eps=1e-3,
                 margin=1e-4, metric_prox=METRIC_PROX, refine_gmm=False, max_samples=3000, random_state=0,
                 verify_samples=DEFAULT_SAMPLES, allow_uncertified=False, progress=None,
                 corrective_rounds=ROUNDS, corrective_tau=TAU, corrective_min_dist=MIN_DIST, warp="auto",
                 gating="smooth", speed_floor="auto"):
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
        self.gating = gating
        self.speed_floor = speed_floor

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
        """The fit path (:func:`~sosdyn.lfd.fit.pipeline.fit`) on the checked parameters and
        demonstrations; its learned attributes become this model's."""
        t_start = time.perf_counter()
        self.check_params()
        if isinstance(demos, PoseDemonstrations):
            raise InputError("these are pose demonstrations (position + orientation). Try: sosdyn.PoseCDSP(**params)"
                             ".fit(demos), the certified CDSP of the 6-D chart state (same parameters).")
        self.__dict__.update(vars(fit_path(check_demonstrations(demos), self.get_params(), self.progress, t_start)))
        return self

    # ------------------------------------------------------------------ prediction
    def _check_fitted(self):
        if not hasattr(self, "C_"):
            raise NotFittedError("this CDSP model is not fitted yet; call fit(demos) first")

    def field(self, X, goal):
        """xdot at the rows of X for the goal ``goal`` (:func:`~sosdyn.lfd.fit.pipeline.field_at`)."""
        return field_at(X, goal, self.scale_, self.mixture_, self.C_, self.field_exps_, self.warp_, self.floor_)

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

    def predictor(self, max_speed=None, **other) -> StatePredictor:
        """A fast one-state evaluator, ``step(x, goal=None) -> xdot`` (:mod:`~sosdyn.lfd.runtime.predictor`):
        ``goal`` moves the goal at run time; ``max_speed`` (data units / s) scales xdot by
        the smooth positive factor of :mod:`~sosdyn.lfd.runtime.states` (|xdot| < max_speed, unchanged below half of
        it; same paths and goal, ``docs/theory.md``)."""
        self.refuse(other, "predictor")
        self._check_fitted()
        return StatePredictor(self.goal_, self.scale_, self.mixture_, self.C_, self.field_exps_,
                              None if self.warp_ is None else maps_of(self.warp_), max_speed,
                              twist_of(self.warp_), self.floor_)

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None, **other):
        """Integrate from x0; pushes [(t, dx)] and goal changes [(t, g)] as in sosdyn.lfd.rollout.

        ``dt`` None means the model's ``dt_``; duration and dt are checked by the integrator, whose
        absolute tolerance is relative to the data's scale ``scale_`` (the same relative accuracy
        in any units) and whose work is bounded (``max_rollout_calls``, ``max_rollout_seconds``).
        ``max_speed``: the field under the speed limit (:func:`~sosdyn.lfd.runtime.states.limit_speed`), as
        ``predictor(max_speed=...)``."""
        self.refuse(other, "rollout")
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
        return check_fit(self.C_, self.field_exps_, self.W_, self.metric_exps_, self.gamma, self.certificate_,
                         self.warp_, n_samples, seed)

    def excursion_bound(self, x0, goal=None, **other) -> float:
        """A certified bound on max_t |x(t) - goal| (data units) from x0: the farthest corner of the
        reach box (:func:`~.reach.reach_box`); inf when the metric is not constant (no bound known)."""
        self.refuse(other, "excursion_bound")
        self._check_fitted()
        goal = self.goal_ if goal is None else as_state(goal, self.dim_, "goal")
        box = reach_box(self, as_state(x0, self.dim_, "x0") - goal + self.goal_)
        if box is None:
            return float("inf")
        lo, hi = (b[0] - self.goal_ for b in box)
        return float(np.linalg.norm(np.maximum(-lo, hi)))

    # ------------------------------------------------------------------ code, files, people
    def to_python(self, max_speed=None, **other) -> str:
        """Source of a standalone numpy module with ``predict(X, goal=None)`` (:mod:`~sosdyn.lfd.runtime.export_python`)."""
        self.refuse(other, "to_python")
        return to_python(self, max_speed)

    def to_cpp(self, namespace=None, max_speed=None, **other) -> str:
        """Source of a header-only C++17 evaluator ``bool predict(const double* x, double* xdot, const
        double* goal = nullptr)`` in ``namespace`` (default cdsp_model; :mod:`~sosdyn.lfd.runtime.export_cpp`)."""
        self.refuse(other, "to_cpp")
        return to_cpp(self, "cdsp_model" if namespace is None else namespace, max_speed)

    def content(self) -> dict:
        """Parameters (``random_state`` recorded as ``seed_``) and the learned state (:mod:`.content`)."""
        self._check_fitted()
        return {"params": dict(self.get_params(), random_state=self.seed_),
                "state": state_record({k: getattr(self, k) for k in STATE_FIELDS})}

    @classmethod
    def from_content(cls, content: dict) -> CDSP:
        """A CDSP (not yet verified) from a file's content; ModelFileError naming the first bad field."""
        params = dict(LEGACY_PARAMS, **need(content, "params", "", dict))   # files older than a parameter
        check_param_names(params, PARAMS)
        model = cls(**params)
        try:
            check_params(params, DEFAULTS)
        except InputError as exc:
            raise ModelFileError(f"invalid params: {exc}") from None
        model.seed_ = resolve_seed(model.random_state)
        metric_degree = Settings.from_params(params).learned_metric_degree
        state = validate_state(need(content, "state", "", dict), model.n_components, model.field_degree,
                               metric_degree, 0.5 * model.eps)
        model.__dict__.update(state)
        return model

    def layout(self) -> Layout:
        names = self.names()
        return Layout(names, (names,), names, names)

    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the demonstrations' first states (without: from the mixture's means), each for
        ``duration`` s (default HORIZON x its demo's duration; 10 s without demos)."""
        self._check_fitted()
        starts = [d.pos[0] for d in demos] if demos else list(self.goal_ + self.scale_ * self.mixture_.means)
        spans = [duration or HORIZON * d.duration for d in demos] if demos else [duration or 10.0] * len(starts)
        runs = [self.rollout(x0, T) for x0, T in zip(starts, spans)]
        return Reproductions(list(demos or []), runs, self.goal_, self.names(), self.units_,
                             self.predict if self.dim_ == 2 else None)

    def summary(self) -> list[str]:
        """The certificate's numbers; the warp and how it was chosen."""
        self._check_fitted()
        r = self.verification_
        lines = [f"min Gram eigenvalue {r.min_gram_eig:.2e}, max sampled generalised eigenvalue "
                 f"{r.max_sampled_eig:.2e} over {r.n_samples} states"]
        if self.warp_ is not None:
            lines.append(f"warp: {r.warp['n_maps']} maps, max Lipschitz number {r.warp['max_lipschitz']:.3f} (< 1)")
        scores = getattr(self, "warp_scores_", {})
        if len(scores) > 1:          # the lowest training deviation is kept (ties: the first, as warp_choice)
            listed = "; ".join(f"{name} {score:.4g}" for name, score in scores.items())
            lines.append(f"warp candidates, training deviation (lower is better): {listed} -> kept "
                         f"{min(scores, key=scores.get)} (the lowest)")
        if self.floor_ is not None:
            zone = f"{self.floor_['radius']:.3g} {self.units_}".strip() if "radius" in self.floor_ else ""
            lines.append(describe(self.floor_, zone))
        return lines

    def iteration_cap(self, rows: list[dict]) -> str | None:
        """The fit's rows against ``max_iter`` and ``tol`` (:func:`~sosdyn.lfd.fit.learner.capped`)."""
        return capped(rows, self.max_iter, self.tol)

    @property
    def n_iter_(self) -> int:
        return len(self.history_)


DEFAULTS = {name: p.default for name, p in inspect.signature(CDSP).parameters.items()}


"""The second-order CDSP estimator: certified motions that may cross themselves; the second-order
family of the model interface (:class:`~.base.MotionModel`).

Model (scaled units, :mod:`sosdyn.lfd.fit.second_order`): e = ((x - g)/s, v T/s),
de/dt' = sum_k h_k(e) F_k e with F_k = [[0, I], [A_k, B_k]]; certificate: one constant M > 0 with
F_k^T M + M F_k <= -2 gamma' M for every k (gamma' = gamma T), checked independently
(:mod:`sosdyn.lfd.fit.second_order.certificate`) before a model is returned. Then from EVERY (x0, v0),
|| (x - g, v) || in the metric decays like exp(-gamma t): x -> g and v -> 0 (docs/theory.md,
"Second order"). The gating h(e) depends on v, so two branches may cross at one x.

Speed limit (``rollout(max_speed=...)``): the whole field (v, a) scaled by the speed limit's factor
lambda(|v| / v_max) > 0 (:func:`~sosdyn.lfd.runtime.states.speed_factor`) is a time change of the certified system (same paths in (x, v), same goal, V still decreasing),
so the position moves at |dx/dt| = lambda |v| <= v_max; the state's v is then not dx/dt, so a
controller that reads the measured velocity cannot apply it: the one-state predictor and the exports
refuse ``max_speed`` (docs/theory.md).
"""
from __future__ import annotations

import inspect
import time
from numbers import Integral

import numpy as np
from threadpoolctl import threadpool_limits

from sosdyn.errors import InputError, ModelFileError, NotCertifiedError, NotFittedError
from ..data.demonstrations import check_demonstrations, sample_step
from ..data.pose import PoseDemonstrations
from ..fit.certificate import DEFAULT_SAMPLES
from ..fit.params import MAX_SEED, check_params, check_solver, resolve_seed
from ..fit.second_order import (METHODS, acceleration_at, check_second_order, energy_violations, excursion_bound,
                                fit_gating, fit_second_order, scaled_samples)
from ..rollout import Trajectory, as_vector
from ..rollout.events import is_positive_number
from ..rollout import rollout as integrate
from ..rollout.quality import HORIZON, reproduction_table
from ..runtime.second_order import SecondOrderPredictor, to_cpp, to_python
from ..runtime.states import as_state, as_states, check_max_speed, speed_factor
from .base import Layout, MotionModel, Reproductions
from .cdsp import DEFAULTS as FIRST_ORDER_DEFAULTS
from .content import SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION, check_param_names, need, second_order_state

MAX_COPIES = 20                 # perturbed copies per sample (each multiplies the data term's rows)
PARAMS = ("n_components", "gamma", "margin", "max_iter", "tol", "metric_prox", "method", "tracking_copies",
          "tracking_sigma", "tracking_rate", "max_samples", "random_state", "verify_samples", "solver")


class SecondOrderCDSP(MotionModel):
    """Learn a certified second-order motion ẍ = a(x, ẋ) from demonstrations (positions + times).

    **Parameters**: ``n_components`` (int or "bic": Gaussians of the gating GMM on (x, v)),
    ``gamma`` (1/s: the certified decay rate of ||(x - g, v)||_M), ``margin`` (the fields' LMI
    margin, scaled units), ``max_iter`` / ``tol`` (alternations, relative cost decrease),
    ``metric_prox`` (proximal weight of the metric step; the joint step uses 1 % of it), ``method``
    ("ica": joint convex steps in (C, M), or "alternating": metric / field steps),
    ``tracking_copies`` / ``tracking_sigma`` / ``tracking_rate`` (perturbed copies of each sample,
    their spread in scaled units and the rate w of their pull-back labels a - w^2 dx - 2 w dv:
    :func:`~sosdyn.lfd.fit.second_order.tracking_samples`; 0 copies: the demos alone),
    ``max_samples``, ``random_state`` (EM and the sampled check), ``verify_samples`` (states of the
    sampled check), ``solver``; ``progress`` (None or a callable, not saved: called with each
    iterate's history row).

    **Learned**: ``goal_``, ``dim_``, ``dt_``, ``units_``, ``columns_`` (as the data's), ``length_scale_`` (s), ``time_scale_`` (T),
    ``mixture_`` (the gating on e), ``C_`` (K, n, 2n) = [A_k, B_k] in scaled units, ``M_`` (2n, 2n),
    ``certificate_`` (:class:`~sosdyn.lfd.fit.second_order.certificate.SecondOrderCertificate`; also
    ``verification_``, with ``certified_`` True, as for CDSP),
    ``energy_violations_`` (how often the training demos themselves break the certified decrease),
    ``history_`` (one row per certified iterate), ``chosen_iter_`` (the row returned: least training
    rollout deviation), ``fit_seconds_``, ``seed_``. Set by ``fit`` only (not in a model file):
    ``energy_violations_``, ``chosen_iter_``, ``fit_seconds_`` and the rows of ``history_``. In data
    units A_k / T^2 and B_k / T: :meth:`fields`.
    """

    name = "CDSP-2"
    file_format, file_version = SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION
    follows_crossings = True

    def __init__(self, n_components=8, gamma=0.1, margin=1e-4, max_iter=50, tol=1e-4, metric_prox=1e-2,
                 method="ica", tracking_copies=2, tracking_sigma=0.1, tracking_rate=3.0, max_samples=3000,
                 random_state=0, verify_samples=DEFAULT_SAMPLES, solver="CLARABEL", progress=None):
        self.n_components = n_components
        self.gamma = gamma
        self.margin = margin
        self.max_iter = max_iter
        self.tol = tol
        self.metric_prox = metric_prox
        self.method = method
        self.tracking_copies = tracking_copies
        self.tracking_sigma = tracking_sigma
        self.tracking_rate = tracking_rate
        self.max_samples = max_samples
        self.random_state = random_state
        self.verify_samples = verify_samples
        self.solver = solver
        self.progress = progress

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in PARAMS}

    def __repr__(self) -> str:
        changed = [f"{k}={v!r}" for k, v in self.get_params().items() if not (v is DEFAULTS[k] or v == DEFAULTS[k])]
        if hasattr(self, "C_"):
            changed.append(f"fitted: K={self.C_.shape[0]}, n={self.dim_}, certified={self.verification_.passed}")
        return f"SecondOrderCDSP({', '.join(changed)})"

    def check_params(self) -> None:
        """Types and ranges (the first-order checks of the shared parameters; InputError with a hint)."""
        check_params({**FIRST_ORDER_DEFAULTS, **self.get_params()}, {**FIRST_ORDER_DEFAULTS, **DEFAULTS})
        check_solver(self.solver)
        if not isinstance(self.method, str) or self.method not in METHODS:
            raise InputError(f"method must be one of {METHODS}, got {self.method!r}. Try: the default, method='ica'.")
        c = self.tracking_copies
        if isinstance(c, (bool, np.bool_)) or not isinstance(c, Integral) or not 0 <= c <= MAX_COPIES:
            raise InputError(f"tracking_copies must be an integer in [0, {MAX_COPIES}], got {c!r}. "
                             "Try: the default, 2.")
        for name in ("tracking_sigma", "tracking_rate"):
            if not is_positive_number(getattr(self, name)):
                raise InputError(f"{name} must be a finite number > 0, got {getattr(self, name)!r}. "
                                 f"Try: the default, {DEFAULTS[name]}.")

    # ------------------------------------------------------------------ fitting
    def fit(self, demos):
        """Learn from Demonstrations (validated first, as :meth:`CDSP.fit`); returns self. Velocities
        and accelerations are derived from the positions and times (one Savitzky-Golay fit per demo);
        a demo's stored velocities are not used.

        Raises NotCertifiedError when the independent check fails (no model is returned then)."""
        with threadpool_limits(limits=1, user_api="blas"):
            return self._fit(demos)

    def _fit(self, demos):
        start = time.perf_counter()
        self.check_params()
        if isinstance(demos, PoseDemonstrations):
            raise InputError("these are pose demonstrations; SecondOrderCDSP learns positions. "
                             "Try: sosdyn.PoseCDSP for poses, or Demonstrations of positions.")
        demos = check_demonstrations(demos)
        seed = resolve_seed(self.random_state)
        K = 1 if self.n_components == "bic" else int(self.n_components)
        scaled = scaled_samples(demos, K, self.max_samples)
        mixture = fit_gating(scaled.E, self.n_components, seed)
        result = fit_second_order(scaled, mixture, float(self.gamma), float(self.margin), int(self.max_iter),
                                  float(self.tol), float(self.metric_prox), self.method, self.solver, self.progress,
                                  tracking=(int(self.tracking_copies), float(self.tracking_sigma),
                                            float(self.tracking_rate), seed))
        report = check_second_order(result.C, result.M, self.gamma, scaled.time, mixture, self.verify_samples, seed)
        if not report.passed:
            raise NotCertifiedError(f"the second-order certificate failed its independent check: {report}",
                                    status="not_certified", hint="a smaller gamma or a larger margin")
        n = demos.dim
        self.seed_, self.dim_, self.goal_, self.dt_ = seed, n, scaled.goal, sample_step(demos)
        self.units_, self.columns_ = demos.units, demos.columns
        self.length_scale_, self.time_scale_, self.window_ = scaled.length, scaled.time, scaled.window
        self.mixture_, self.C_, self.M_, self.margin_ = mixture, result.C, result.M, result.margin
        self.verification_, self.certified_ = report, True
        self.history_, self.chosen_iter_ = result.history, result.chosen
        self.energy_violations_ = energy_violations(result.M, report.gamma_scaled, scaled.E,
                                                    np.hstack([scaled.E[:, n:], scaled.Ea]))
        self.fit_seconds_ = time.perf_counter() - start
        return self

    @property
    def certificate_(self):
        """The certificate as last checked (:class:`~sosdyn.lfd.fit.second_order.certificate.SecondOrderCertificate`:
        M, gamma, per-LMI margins, the verdict); ``verification_`` under the first-order name."""
        self._check_fitted()
        return self.verification_

    # ------------------------------------------------------------------ prediction
    def _check_fitted(self):
        if not hasattr(self, "C_"):
            raise NotFittedError("this SecondOrderCDSP model is not fitted yet; call fit(demos) first")

    def acceleration(self, X, V, goal):
        """Accelerations (m, n) at the rows of X and V for the goal ``goal`` (no input checks)."""
        return acceleration_at(X, V, goal, self.length_scale_, self.time_scale_, self.mixture_, self.C_)

    def predict(self, X, V):
        """Accelerations (m, n) at positions X and velocities V ((m, n) each, or one state (n,))."""
        self._check_fitted()
        X, V = as_states(X, self.dim_, "X"), as_states(V, self.dim_, "V")
        if X.shape != V.shape:
            raise InputError(f"X has {X.shape[0]} states but V has {V.shape[0]}; pass one velocity per position.")
        with np.errstate(over="ignore", invalid="ignore"):
            A = self.acceleration(X, V, self.goal_)
        if not np.isfinite(A).all():
            raise InputError("the states are so far from the data that the acceleration overflows float. "
                             "Try: states within a few orders of magnitude of the demonstrations.")
        return A

    def fields(self):
        """(A, B) per component in data units: A_k / T^2 (K, n, n) and B_k / T (K, n, n)."""
        self._check_fitted()
        n, T = self.dim_, self.time_scale_
        return self.C_[:, :, :n] / T ** 2, self.C_[:, :, n:] / T

    def predictor(self, max_speed=None, **other) -> SecondOrderPredictor:
        """A one-state evaluator ``step(x, v, goal=None) -> acceleration`` (:mod:`~sosdyn.lfd.runtime.second_order`);
        ``max_speed`` is refused (module docstring: it applies to rollouts)."""
        self.refuse(other, "predictor")
        self._no_speed_limit(max_speed)
        self._check_fitted()
        return SecondOrderPredictor(self.goal_, self.length_scale_, self.time_scale_, self.mixture_, self.C_)

    def to_python(self, max_speed=None, **other) -> str:
        """A standalone Python module (numpy only) with ``acceleration(X, V, goal=None)``
        (:mod:`~sosdyn.lfd.runtime.second_order`); ``max_speed`` refused as by :meth:`predictor`."""
        self.refuse(other, "to_python")
        self._no_speed_limit(max_speed)
        return to_python(self)

    def to_cpp(self, namespace=None, max_speed=None, **other) -> str:
        """A header-only C++17 ``bool acceleration(const double* x, const double* v, double* a, const
        double* goal = nullptr)`` in ``namespace`` (default second_order_model); ``max_speed`` refused."""
        self.refuse(other, "to_cpp")
        self._no_speed_limit(max_speed)
        return to_cpp(self, "second_order_model" if namespace is None else namespace)

    @staticmethod
    def _no_speed_limit(max_speed) -> None:
        if check_max_speed(max_speed) is not None:
            raise InputError("max_speed: a second-order model's speed limit is a time change of its state (x, v), "
                             "which a controller reading the measured velocity cannot apply. Try: "
                             "rollout(..., max_speed=...) (sosdyn rollout --max-speed) to plan a limited motion, "
                             "or no limit here.")

    def excursion_bound(self, x0, v0=None, goal=None, **other) -> float:
        """The certified bound on max_t |x(t) - goal| (data units) from (x0, v0): the projection on x
        of the ellipsoid {e : e^T M e <= e0^T M e0} (:func:`~sosdyn.lfd.fit.second_order.certificate.excursion_bound`)."""
        self.refuse(other, "excursion_bound")
        self._check_fitted()
        x0, v0, goal = self._start(x0, v0, goal)
        e0 = np.concatenate([(x0 - goal) / self.length_scale_, v0 * self.time_scale_ / self.length_scale_])
        return excursion_bound(self.M_, e0) * self.length_scale_

    def _start(self, x0, v0, goal):
        n = self.dim_
        x0 = as_state(x0, n, "x0")
        v0 = np.zeros(n) if v0 is None else as_state(v0, n, "v0")
        return x0, v0, self.goal_ if goal is None else as_state(goal, n, "goal")

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None, v0=None,
                **other) -> Trajectory:
        """Integrate (x, v) from (x0, v0) (v0 None: at rest) for ``duration`` s on a grid of step ``dt``
        (None: ``dt_``). Pushes ``[(t, dx)]`` with dx of shape (n,) (position) or (2n,) (position and
        velocity); goal changes ``[(t, g)]`` (the motion translates); ``max_speed``: the field (v, a)
        scaled by the speed limit's factor of |v| (< max_speed), a time change (module docstring). The Trajectory has
        ``vel`` (dx/dt); a push's ``before`` / ``after`` are (x, v) states (:func:`sosdyn.lfd.rollout.rollout`)."""
        self.refuse(other, "rollout")
        self._check_fitted()
        n = self.dim_
        x0, v0, goal = self._start(x0, v0, goal)
        pushes = _lifted(perturbations, n, "perturbation", (n, 2 * n))
        goals = _lifted(goal_changes, n, "goal change", (n,))
        max_speed = check_max_speed(max_speed)

        def field(Y, G):
            return speed_factor(Y[:, n:], max_speed) * np.hstack([Y[:, n:], self.acceleration(Y[:, :n], Y[:, n:], G[:n])])

        traj = integrate(field, np.concatenate([x0, v0]), duration=duration, dt=self.dt_ if dt is None else dt,
                         goal=np.concatenate([goal, np.zeros(n)]), perturbations=pushes, goal_changes=goals,
                         scale=self.length_scale_)
        events = [dict(e, before=e["before"][:n], after=e["after"][:n]) if e["kind"] == "goal_change" else e
                  for e in traj.events]
        return Trajectory(traj.t, traj.pos[:, :n], traj.goal_history[:, :n], events,
                          vel=speed_factor(traj.pos[:, n:], max_speed) * traj.pos[:, n:])

    # ------------------------------------------------------------------ evidence and files
    def verify(self, n_samples=None, seed=None):
        """The independent check again (exact LMIs, sampled decrease at ``n_samples`` states drawn
        with ``seed``; defaults ``verify_samples`` and ``seed_``)."""
        self._check_fitted()
        if seed is not None and (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, Integral)
                                 or not 0 <= seed <= MAX_SEED):
            raise InputError(f"seed must be None or an integer in [0, {MAX_SEED}], got {seed!r}")
        return check_second_order(self.C_, self.M_, self.gamma, self.time_scale_, self.mixture_,
                                  self.verify_samples if n_samples is None else n_samples,
                                  self.seed_ if seed is None else seed)

    def score(self, demos) -> list[dict]:
        """Per demonstration, its reproduction from its first position and velocity by semi-implicit
        Euler at step ``dt_`` (as the fit's training rollouts), scored as :meth:`CDSP.score`
        (:func:`~sosdyn.lfd.rollout.quality.reproduction_table`)."""
        self._check_fitted()
        demos = check_demonstrations(demos, goal_tol=np.inf)
        n, dt = self.dim_, self.dt_
        if demos.dim != n:
            raise InputError(f"the demonstrations are {demos.dim}-D but the model is {n}-D. Try: the "
                             "demonstrations it was fitted to.")

        def step(Z):            # explicit Euler on z = (x, v) with z' = (v + dt a, a): semi-implicit Euler
            A = self.acceleration(Z[:, :n], Z[:, n:], self.goal_)
            return np.hstack([Z[:, n:] + dt * A, A])
        starts = np.array([np.concatenate([d.pos[0], d.vel[0]]) for d in demos])
        return reproduction_table(step, demos, self.goal_, dt, starts)

    def content(self) -> dict:
        """The parameters (``random_state`` = the seed used) and the learned values (plain lists)."""
        self._check_fitted()
        mix = self.mixture_
        return {"params": dict(self.get_params(), random_state=self.seed_),
                "state": {"goal": self.goal_, "dt": self.dt_, "length_scale": self.length_scale_,
                          "time_scale": self.time_scale_, "window": self.window_, "weights": mix.weights,
                          "means": mix.means, "covariances": mix.covariances, "C": self.C_, "M": self.M_,
                          "margin": self.margin_, "units": self.units_, "columns": self.columns_}}

    @classmethod
    def from_content(cls, content: dict) -> SecondOrderCDSP:
        """A model (not yet verified) from a file's content (:func:`~.content.second_order_state`)."""
        params = need(content, "params", "", dict)
        check_param_names(params, PARAMS)
        model = cls(**params)
        try:
            model.check_params()
        except InputError as exc:
            raise ModelFileError(f"invalid params: {exc}") from None
        st = second_order_state(need(content, "state", "", dict))
        n = len(st["goal"])
        model.seed_, model.dim_, model.goal_, model.dt_ = int(params["random_state"]), n, st["goal"], st["dt"]
        model.length_scale_, model.time_scale_, model.margin_ = st["length_scale"], st["time_scale"], st["margin"]
        model.window_, model.units_, model.columns_ = st["window"], st["units"], st["columns"]
        model.mixture_, model.C_, model.M_, model.history_ = st["mixture"], st["C"], st["M"], []
        return model

    # ------------------------------------------------------------------ for people
    def layout(self) -> Layout:
        names = self.names()
        return Layout(names, (names, names + tuple(f"v{a}" for a in names)), names, names)

    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the demonstrations' first (x, v) (without: from the gating mixture's means),
        each for ``duration`` s (default HORIZON x its demo's duration; 10 s without demos)."""
        self._check_fitted()
        s, T, n = self.length_scale_, self.time_scale_, self.dim_
        starts = [(d.pos[0], d.vel[0]) for d in demos] if demos else \
            [(self.goal_ + s * m[:n], m[n:] * s / T) for m in self.mixture_.means]
        spans = [duration or HORIZON * d.duration for d in demos] if demos else [duration or 10.0] * len(starts)
        runs = [self.rollout(x0, span, v0=v0) for (x0, v0), span in zip(starts, spans)]
        return Reproductions(list(demos or []), runs, self.goal_, self.names(), self.units_)

    def summary(self) -> list[str]:
        """The certificate's numbers and how often the demonstrations themselves break its decrease."""
        r = self.verification_
        worst = min((m if m is not None else -np.inf) for m in r.proven_margins)
        lines = [f"metric M and {len(r.proven_margins)} LMIs proven in exact arithmetic (min margin {worst:.2e}), "
                 f"max sampled decrease rate {r.max_sampled_rate:.2e} over {r.n_samples} states x 2 gatings"]
        v = getattr(self, "energy_violations_", None)
        if v:
            lines.append(f"the demonstrations decay slower than certified at {v['slower_than_certified']:.0%} of "
                         f"{v['samples']} samples and gain M-energy at {v['energy_gain']:.0%}")
        return lines

def _lifted(items, n: int, kind: str, sizes: tuple) -> list:
    """``[(time, vector)]`` with vectors of a length in ``sizes``, an n-vector lifted to (vector, 0) in
    the state (x, v) (times are checked by the integrator's :func:`~sosdyn.lfd.rollout.parse_events`)."""
    try:
        pairs = [(t, as_vector(v, None, f"{kind} {i} vector")) for i, (t, v) in enumerate(items)]
    except InputError:
        raise
    except (TypeError, ValueError):
        raise InputError(f"{kind}s must be a list of pairs (time, vector), got {items!r}.") from None
    bad = [i for i, (_, v) in enumerate(pairs) if v.size not in sizes]
    if bad:
        raise InputError(f"{kind} {bad[0]} vector has {pairs[bad[0]][1].size} entries; expected "
                         + (f"{n} (position) or {2 * n} (position and velocity)." if len(sizes) > 1 else f"{n}."))
    return [(t, np.concatenate([v, np.zeros(n)]) if v.size == n else v) for t, v in pairs]


DEFAULTS = {name: p.default for name, p in inspect.signature(SecondOrderCDSP).parameters.items()}

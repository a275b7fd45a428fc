"""The second-order CDSP estimator: certified motions that may cross themselves; the second-order
family of the model interface (:class:`~.base.MotionModel`).

Two fields (``field``), scaled units e = ((x - g)/s, v T/s) (:mod:`sosdyn.lfd.fit.second_order`):

* ``"tracking"`` (default): the demonstrations' accelerations tracked by a kernel average in (x, v)
  with a pull back to them (:mod:`~sosdyn.lfd.fit.second_order.tracking`), filtered so that
  V(e) = e^T M e rises only by what an energy tank b pays (:mod:`~sosdyn.lfd.fit.second_order.tank`);
  the state is (x, v, b), b(0) = beta V(e(0)). Certificate: a witness field C_0 with
  F_0^T M + M F_0 <= -2 gamma' M (exact), so W = V + b decays like exp(-2 gamma t) from EVERY
  (x0, v0, b0): x -> g, v -> 0, and |x - g| stays within the certified radius of V(e0) + b0.
* ``"mixture"``: de/dt' = sum_k h_k(e) F_k e with F_k = [[0, I], [A_k, B_k]]; certificate: one
  constant M > 0 with F_k^T M + M F_k <= -2 gamma' M for every k (gamma' = gamma T); the tank stays 0.

Both are checked independently (:mod:`sosdyn.lfd.fit.second_order.certificate`) before a model is
returned (docs/theory.md, "Second order"); the fit path is :mod:`sosdyn.lfd.fit.second_order.pipeline`. The field depends on v, so two branches may cross at one x.

Speed limit (``rollout(max_speed=...)``): the whole field (v, a, db/dt) scaled by the speed limit's
factor lambda(|v| / v_max) > 0 (:func:`~sosdyn.lfd.runtime.states.speed_factor`) is a time change of
the certified system (same paths, same goal, V + b still decreasing), so |dx/dt| = lambda |v| <
v_max; the state's v is then not dx/dt, so a controller that reads the measured velocity cannot apply
it: the predictor and the exports refuse ``max_speed``.
"""
from __future__ import annotations

import inspect
import time
from numbers import Integral

import numpy as np
from threadpoolctl import threadpool_limits

from sosdyn.errors import InputError, ModelFileError, NotFittedError
from ..data.demonstrations import check_demonstrations
from ..data.pose import PoseDemonstrations
from ..fit.certificate import DEFAULT_SAMPLES
from ..fit.params import MAX_SEED, resolve_seed
from ..fit.second_order import acceleration_at, excursion_bound
from ..fit.second_order.certificate import mixture_summary
from ..fit.second_order.learner import capped
from ..fit.second_order.params import ONLY_WITH, PARAMS, TRACKING_PARAMS, check_params
from ..fit.second_order.pipeline import check_field, fit as fit_path
from ..fit.second_order.tank import TankField, derivatives_at, initial_tank, scaled_states, tank_summary
from ..fit.second_order.tracking import kernel_widths
from ..rollout import Trajectory
from ..rollout import rollout as integrate
from ..rollout.events import lifted
from ..rollout.quality import HORIZON, reproduction_table
from ..runtime.second_order import SecondOrderPredictor, TankPredictor, to_cpp, to_python
from ..runtime.states import as_levels, as_state, as_states, check_max_speed, speed_factor
from .base import Layout, MotionModel, Reproductions
from .cdsp import DEFAULTS as FIRST_ORDER_DEFAULTS
from .content import SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION, check_param_names, need, second_order_state


class SecondOrderCDSP(MotionModel):
    """Learn a certified second-order motion ẍ = a(x, ẋ) from demonstrations (positions + times).

    **Parameters**: ``field`` ("tracking" or "mixture", module docstring); ``gamma`` (1/s: the
    certified decay rate of ||(x - g, v)||_M, with the tank: of sqrt(V + b)), ``margin`` (the fields'
    LMI margin, scaled units), ``tracking_rate`` (w: the critically damped pull back to the demos,
    scaled units), ``max_samples``, ``random_state`` (EM, subsampling and the sampled check),
    ``verify_samples`` (states of the sampled check), ``solver``; ``progress`` (None or a callable,
    not saved: called with each iterate's history row). Tracking only: ``position_width`` /
    ``velocity_width`` (the kernel's widths h_x, h_v in scaled units) and ``tank_factor`` (beta is
    this times the largest tank a training demo needs). Mixture only: ``n_components`` (int or
    "bic": Gaussians of the gating GMM on (x, v)), ``max_iter`` / ``tol`` (alternations, relative
    cost decrease), ``metric_prox`` (proximal weight of the metric step; the joint step uses 1 %
    of it), ``solver_method`` ("ica": joint convex steps in (C, M); "alternating" or "energy": metric /
    field steps, :func:`~sosdyn.lfd.fit.second_order.fit_second_order`), ``tracking_copies`` /
    ``tracking_sigma`` (perturbed copies of each sample and their spread, labelled a - w^2 dx - 2 w dv:
    :func:`~sosdyn.lfd.fit.second_order.tracking_samples`; 0 copies: the demos alone). The names, which
    field each applies to and the checks: :mod:`sosdyn.lfd.fit.second_order.params`.

    **Learned**: ``goal_``, ``dim_``, ``dt_``, ``units_``, ``columns_`` (as the data's), ``length_scale_`` (s), ``time_scale_`` (T),
    ``mixture_`` (the gating on e; None for tracking), ``tank_`` (the tracking field,
    :class:`~sosdyn.lfd.fit.second_order.tank.TankField`; None for the mixture), ``C_`` (K, n, 2n) =
    [A_k, B_k] in scaled units (tracking: K = 1, the witness C_0), ``M_`` (2n, 2n), ``tank_needs_``
    (each training demo's tank need beta_d),
    ``certificate_`` (:class:`~sosdyn.lfd.fit.second_order.certificate.SecondOrderCertificate`; also
    ``verification_``, with ``certified_`` True), ``energy_violations_`` (how often the training demos
    break the certified decrease), ``history_`` (one row per certified iterate), ``chosen_iter_`` (the
    row returned: least training rollout deviation), ``fit_seconds_``, ``seed_``. Set by ``fit`` only:
    ``energy_violations_``, ``tank_needs_``, ``chosen_iter_``, ``fit_seconds_`` and the rows of
    ``history_``. In data units A_k / T^2 and B_k / T: :meth:`fields`.
    """

    name = "CDSP-2"
    file_format, file_version = SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION
    follows_crossings = True
    only_with = ONLY_WITH

    def __init__(self, n_components=8, gamma=0.1, margin=1e-4, max_iter=50, tol=1e-4, metric_prox=1e-2,
                 solver_method="ica", tracking_copies=2, tracking_sigma=0.1, tracking_rate=3.0, max_samples=3000,
                 random_state=0, verify_samples=DEFAULT_SAMPLES, solver="CLARABEL", field="tracking",
                 position_width=0.03, velocity_width=0.3, tank_factor=1.25, progress=None):
        self.n_components = n_components
        self.gamma = gamma
        self.margin = margin
        self.max_iter = max_iter
        self.tol = tol
        self.metric_prox = metric_prox
        self.solver_method = solver_method
        self.tracking_copies = tracking_copies
        self.tracking_sigma = tracking_sigma
        self.tracking_rate = tracking_rate
        self.max_samples = max_samples
        self.random_state = random_state
        self.verify_samples = verify_samples
        self.solver = solver
        self.field = field
        self.position_width = position_width
        self.velocity_width = velocity_width
        self.tank_factor = tank_factor
        self.progress = progress

    def get_params(self) -> dict:
        return {k: getattr(self, k) for k in PARAMS}

    def __repr__(self) -> str:
        changed = [f"{k}={v!r}" for k, v in self.get_params().items() if not (v is DEFAULTS[k] or v == DEFAULTS[k])]
        if hasattr(self, "C_"):
            changed.append(f"fitted: K={self.C_.shape[0]}, n={self.dim_}, certified={self.verification_.passed}"
                           + (f", beta={self.tank_.beta:.3g}" if self.tank_ is not None else ""))
        return f"SecondOrderCDSP({', '.join(changed)})"

    def check_params(self) -> None:
        """Types and ranges (:func:`~sosdyn.lfd.fit.second_order.params.check_params`; InputError with a hint)."""
        check_params(self.get_params(), DEFAULTS, FIRST_ORDER_DEFAULTS)

    # ------------------------------------------------------------------ fitting
    def fit(self, demos):
        """Learn from Demonstrations (validated first, as :meth:`CDSP.fit`); returns self. Velocities and
        accelerations come from one Savitzky-Golay fit per demo (stored velocities are not used).
        NotCertifiedError when the independent check fails (no model is returned then)."""
        with threadpool_limits(limits=1, user_api="blas"):
            return self._fit(demos)

    def _fit(self, demos):
        start = time.perf_counter()
        self.check_params()
        if isinstance(demos, PoseDemonstrations):
            raise InputError("these are pose demonstrations; SecondOrderCDSP learns positions. "
                             "Try: sosdyn.PoseCDSP for poses, or Demonstrations of positions.")
        demos = check_demonstrations(demos)
        self.__dict__.update(fit_path(demos, self.get_params(), resolve_seed(self.random_state), self.progress))
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

    def derivatives(self, X, V, goal, tank):
        """(accelerations (m, n), tank rates db/dt (m,) per s) at the rows of X and V with tank levels
        ``tank`` (m,) for the goal ``goal`` (no input checks; the mixture's tank stays 0)."""
        if self.tank_ is None:
            return (acceleration_at(X, V, goal, self.length_scale_, self.time_scale_, self.mixture_, self.C_),
                    np.zeros(len(X)))
        return derivatives_at(self.tank_, X, V, goal, self.length_scale_, self.time_scale_, tank)

    def initial_tank(self, X, V, goal=None) -> np.ndarray:
        """The tank levels b(0) = beta V(e) (m,) of motions starting at the rows of X and V (0 for the mixture)."""
        goal = self.goal_ if goal is None else goal
        if self.tank_ is None:
            return np.zeros(len(X))
        return initial_tank(self.tank_, scaled_states(X, V, goal, self.length_scale_, self.time_scale_))

    def predict(self, X, V, tank=None):
        """Accelerations (m, n) at positions X and velocities V ((m, n) each, or one state (n,)) with
        tank levels ``tank`` ((m,) or a number; None: :meth:`initial_tank`, a motion starting there)."""
        self._check_fitted()
        X, V = as_states(X, self.dim_, "X"), as_states(V, self.dim_, "V")
        if X.shape != V.shape:
            raise InputError(f"X has {X.shape[0]} states but V has {V.shape[0]}; pass one velocity per position.")
        b = self.initial_tank(X, V) if tank is None else as_levels(tank, len(X))
        with np.errstate(over="ignore", invalid="ignore"):
            A = self.derivatives(X, V, self.goal_, b)[0]
        if not np.isfinite(A).all():
            raise InputError("the states are so far from the data that the acceleration overflows float. "
                             "Try: states within a few orders of magnitude of the demonstrations.")
        return A

    def fields(self):
        """(A, B) per component in data units: A_k / T^2 (K, n, n) and B_k / T (K, n, n) (tracking: the witness)."""
        self._check_fitted()
        n, T = self.dim_, self.time_scale_
        return self.C_[:, :, :n] / T ** 2, self.C_[:, :, n:] / T

    def predictor(self, max_speed=None, **other) -> SecondOrderPredictor | TankPredictor:
        """A one-state evaluator ``step(x, v, goal=None) -> acceleration`` (:mod:`~sosdyn.lfd.runtime.second_order`;
        tracking: ``step(x, v, goal=None, dt=None)``, which keeps the tank and advances it by ``dt``);
        ``max_speed`` is refused (module docstring: it applies to rollouts)."""
        self.refuse(other, "predictor")
        self._no_speed_limit(max_speed)
        self._check_fitted()
        if self.tank_ is not None:
            return TankPredictor(self.tank_, self.goal_, self.length_scale_, self.time_scale_)
        return SecondOrderPredictor(self.goal_, self.length_scale_, self.time_scale_, self.mixture_, self.C_)

    def to_python(self, max_speed=None, **other) -> str:
        """A standalone Python module (numpy only) with ``acceleration(X, V, goal=None)`` (tracking:
        ``acceleration(X, V, goal=None, tank=None)``, ``derivatives`` and ``initial_tank``)
        (:mod:`~sosdyn.lfd.runtime.second_order`); ``max_speed`` refused as by :meth:`predictor`."""
        self.refuse(other, "to_python")
        self._no_speed_limit(max_speed)
        return to_python(self)

    def to_cpp(self, namespace=None, max_speed=None, **other) -> str:
        """A header-only C++17 ``bool acceleration(const double* x, const double* v, double* a, const
        double* goal = nullptr)`` (tracking: also with a tank, ``double* tank, double dt`` before ``goal``,
        and ``initial_tank``) in ``namespace`` (default second_order_model); ``max_speed`` refused."""
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
        """The certified bound on max_t |x(t) - goal| (data units) from (x0, v0) with a full tank: the
        projection on x of the ellipsoid {e : e^T M e <= (1 + beta) e0^T M e0} (beta = 0 for the
        mixture; :func:`~sosdyn.lfd.fit.second_order.certificate.excursion_bound`)."""
        self.refuse(other, "excursion_bound")
        self._check_fitted()
        x0, v0, goal = self._start(x0, v0, goal)
        e0 = scaled_states(x0[None], v0[None], goal, self.length_scale_, self.time_scale_)[0]
        beta = 0.0 if self.tank_ is None else self.tank_.beta
        return excursion_bound(self.M_, e0) * np.sqrt(1.0 + beta) * self.length_scale_

    def _start(self, x0, v0, goal):
        n = self.dim_
        x0 = as_state(x0, n, "x0")
        v0 = np.zeros(n) if v0 is None else as_state(v0, n, "v0")
        return x0, v0, self.goal_ if goal is None else as_state(goal, n, "goal")

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None, v0=None,
                **other) -> Trajectory:
        """Integrate (x, v, b) from (x0, v0) (v0 None: at rest) and a full tank (:meth:`initial_tank`)
        for ``duration`` s on a grid of step ``dt`` (None: ``dt_``). Pushes ``[(t, dx)]`` with dx of
        shape (n,) (position) or (2n,) (position and velocity; the tank keeps its level); goal changes
        ``[(t, g)]`` (the motion translates); ``max_speed``: the field (v, a, db/dt) scaled by
        the speed limit's factor of |v| (< max_speed), a time change (module docstring). The Trajectory has ``vel`` (dx/dt);
        a push's ``before`` / ``after`` are (x, v) states (:func:`sosdyn.lfd.rollout.rollout`)."""
        self.refuse(other, "rollout")
        self._check_fitted()
        n = self.dim_
        x0, v0, goal = self._start(x0, v0, goal)
        pushes = lifted(perturbations, n, "perturbation", (n, 2 * n), 2 * n + 1)
        goals = lifted(goal_changes, n, "goal change", (n,), 2 * n + 1)
        max_speed = check_max_speed(max_speed)

        def field(Y, G):
            A, bdot = self.derivatives(Y[:, :n], Y[:, n:2 * n], G[:n], Y[:, 2 * n])
            return speed_factor(Y[:, n:2 * n], max_speed) * np.hstack([Y[:, n:2 * n], A, bdot[:, None]])

        b0 = self.initial_tank(x0[None], v0[None], goal)
        traj = integrate(field, np.concatenate([x0, v0, b0]), duration=duration, dt=self.dt_ if dt is None else dt,
                         goal=np.concatenate([goal, np.zeros(n + 1)]), perturbations=pushes, goal_changes=goals,
                         scale=self.length_scale_)
        cut = {"goal_change": n, "push": 2 * n}
        events = [dict(e, before=e["before"][:cut[e["kind"]]], after=e["after"][:cut[e["kind"]]]) for e in traj.events]
        return Trajectory(traj.t, traj.pos[:, :n], traj.goal_history[:, :n], events,
                          vel=speed_factor(traj.pos[:, n:2 * n], max_speed) * traj.pos[:, n:2 * n])

    # ------------------------------------------------------------------ evidence and files
    def verify(self, n_samples=None, seed=None):
        """The independent check again (exact LMIs, sampled decrease at ``n_samples`` states drawn
        with ``seed``; defaults ``verify_samples`` and ``seed_``)."""
        self._check_fitted()
        if seed is not None and (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, Integral)
                                 or not 0 <= seed <= MAX_SEED):
            raise InputError(f"seed must be None or an integer in [0, {MAX_SEED}], got {seed!r}")
        n_samples, seed = self.verify_samples if n_samples is None else n_samples, self.seed_ if seed is None else seed
        return check_field(self.tank_, self.mixture_, self.C_, self.M_, self.gamma, self.time_scale_, n_samples, seed)

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

        def step(Z):            # explicit Euler on z = (x, v, b) with z' = (v + dt a, a, db/dt): semi-implicit Euler
            A, bdot = self.derivatives(Z[:, :n], Z[:, n:2 * n], self.goal_, Z[:, 2 * n])
            return np.hstack([Z[:, n:2 * n] + dt * A, A, bdot[:, None]])
        X0, V0 = np.array([d.pos[0] for d in demos]), np.array([d.vel[0] for d in demos])
        starts = np.hstack([X0, V0, self.initial_tank(X0, V0)[:, None]])
        return reproduction_table(step, demos, self.goal_, dt, starts)

    def content(self) -> dict:
        """The parameters (``random_state`` = the seed used) and the learned values (plain lists)."""
        self._check_fitted()
        mix, tank = self.mixture_, self.tank_
        own = ({"samples": tank.samples, "sample_accelerations": tank.accelerations, "beta": tank.beta}
               if tank is not None else {"weights": mix.weights, "means": mix.means, "covariances": mix.covariances})
        return {"params": dict(self.get_params(), random_state=self.seed_),
                "state": {"goal": self.goal_, "dt": self.dt_, "length_scale": self.length_scale_,
                          "time_scale": self.time_scale_, "window": self.window_, **own, "C": self.C_, "M": self.M_,
                          "margin": self.margin_, "units": self.units_, "columns": self.columns_}}

    @classmethod
    def from_content(cls, content: dict) -> SecondOrderCDSP:
        """A model (not yet verified) from a file's content (:func:`~.content.second_order_state`)."""
        params = need(content, "params", "", dict)
        params = {**{k: "mixture" if k == "field" else DEFAULTS[k] for k in TRACKING_PARAMS if k not in params},
                  **params}                       # files older than the tracking field hold mixtures
        if "method" in params and "solver_method" not in params:    # files older than the first-order name
            params["solver_method"] = params.pop("method")
        check_param_names(params, PARAMS)
        model = cls(**params)
        try:
            model.check_params()
        except InputError as exc:
            raise ModelFileError(f"invalid params: {exc}") from None
        st = second_order_state(need(content, "state", "", dict), model.field)
        n = len(st["goal"])
        model.seed_, model.dim_, model.goal_, model.dt_ = int(params["random_state"]), n, st["goal"], st["dt"]
        model.length_scale_, model.time_scale_, model.margin_ = st["length_scale"], st["time_scale"], st["margin"]
        model.window_, model.units_, model.columns_ = st["window"], st["units"], st["columns"]
        model.mixture_, model.C_, model.M_, model.history_ = st.get("mixture"), st["C"], st["M"], []
        model.tank_ = None if model.field == "mixture" else TankField(
            st["samples"], st["sample_accelerations"], kernel_widths(n, model.position_width, model.velocity_width),
            float(model.tracking_rate), st["M"], st["C"][0], float(model.gamma) * st["time_scale"], st["beta"])
        return model

    # ------------------------------------------------------------------ for people
    def layout(self) -> Layout:
        names = self.names()
        return Layout(names, (names, names + tuple(f"v{a}" for a in names)), names, names)

    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the demonstrations' first (x, v) (without: from the gating mixture's means, or
        eight of the tracked samples), each for ``duration`` s (default HORIZON x its demo's duration;
        10 s without demos)."""
        self._check_fitted()
        s, T, n = self.length_scale_, self.time_scale_, self.dim_
        own = self.mixture_.means if self.tank_ is None else \
            self.tank_.samples[np.linspace(0, len(self.tank_.samples) - 1, 8).astype(int)]
        starts = [(d.pos[0], d.vel[0]) for d in demos] if demos else [(self.goal_ + s * m[:n], m[n:] * s / T) for m in own]
        spans = [duration or HORIZON * d.duration for d in demos] if demos else [duration or 10.0] * len(starts)
        runs = [self.rollout(x0, span, v0=v0) for (x0, v0), span in zip(starts, spans)]
        return Reproductions(list(demos or []), runs, self.goal_, self.names(), self.units_)

    def summary(self) -> list[str]:
        """The certificate's numbers and how often the demonstrations themselves break its decrease."""
        if self.tank_ is not None:
            return tank_summary(self.verification_, self.tank_.beta, getattr(self, "tank_needs_", None))
        return mixture_summary(self.verification_, getattr(self, "energy_violations_", None))

    def iteration_cap(self, rows: list[dict]) -> str | None:
        """The mixture's fit loop against ``max_iter`` and ``tol`` (:func:`~sosdyn.lfd.fit.second_order.learner.capped`;
        the tracking field does not iterate)."""
        return capped(rows, self.max_iter, self.tol)

DEFAULTS = {name: p.default for name, p in inspect.signature(SecondOrderCDSP).parameters.items()}

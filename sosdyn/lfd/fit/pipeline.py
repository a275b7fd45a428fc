"""The fit path of CDSP, top-down: demonstrations -> warp candidates -> core fits -> choice.

:func:`fit` is the whole path (``CDSP.fit`` calls it once and keeps the returned :class:`Fit`'s
learned attributes):

1. **warp candidates** (:func:`fit`): the parameter ``warp`` names one candidate ("none", or one
   fixed warp) or, for "auto", no warp and each :data:`~.warp.AUTO_WARPS`; a warped candidate's
   bumps (and a twist, :mod:`.composite`) are fitted to the demonstrations in the data's units
   (:func:`warp_maps`, :mod:`.warp`, :mod:`.twist`);
2. **core fits** (:func:`candidate_fits`, :func:`fit_core`): one per distinct warp, plain
   (:func:`fit_plain`) or with corrective rounds (:func:`~.rounds.corrective_fits`). A plain fit:
   the samples scaled, z = (x - x*)/s (:func:`scaled_data`), warped, u = phi(z), udot = J_phi(z) zdot
   (:func:`warped_data`); EM on [u, udot] (:mod:`.gmm`); the fields and the metric
   (:func:`~.learner.learn`); the certificate (:func:`~.certificate.certify`) and its independent
   check (:func:`check_fit`), which must pass;
3. **choice** (:func:`~.rounds.warp_choice`): among the certified candidates, the one whose Euler
   rollouts from the training demonstrations' starts deviate least from them (when even that one
   deviates by more than :data:`~.warp.ESCALATE` times the data's diagonal, the
   :data:`~.warp.ESCALATE_WARPS` are fitted too and the choice is made again among all); all candidates'
   rollouts in one Euler loop (:func:`block_field`: every candidate's bumps per row, its weights
   in one log-sum-exp; each candidate stops by its own rest test), the same numbers as one loop
   per candidate. ``timings_`` of an "auto" fit add ``candidates_s`` (warps and core fits) and
   ``choice_s`` (the rollouts);
4. **speed floor** (:mod:`.floor`, parameter ``speed_floor``): a time change sigma(x) in [1, BOOST] of
   the kept field, chosen ("auto") as the least that makes the training reproductions arrive in time
   (``floor_``: None or {"rate": kappa, "boost": BOOST}; ``floor_arrivals_``: each candidate's worst
   training arrival ratio).

Every candidate and every corrective round uses the one integer seed resolved from
``random_state`` at the start; progress rows are tagged with the candidate (``warp``) and the
round (``round``).
"""
from __future__ import annotations

import time
import warnings
from dataclasses import replace

import numpy as np

from sosdyn.errors import InputError, NotCertifiedError
from sosdyn.poly import monomial_values
from ..data.demonstrations import Demonstrations, sample_step
from .certificate import CertificateReport, certify, check_certificate, collapse_diagnostic, extract_certificate
from .contraction import eval_fields, field_exponents, metric_exponents
from .corrective import score_steps
from .floor import BOOST, floor_choice, floor_steps, floor_terms, floored
from .gmm import (FADE, MIN_SAMPLES_PER_COMPONENT, PositionMixture, block_log_joint, fit_joint_gmm, gate_bound, gmr_cost,
                  responsibilities_of, weights_from, with_bound)
from .learner import History, Settings, learn, subsample
from .params import resolve_seed, warp_settings
from .rounds import corrective_fits, warp_choice
from .composite import block_pull, check as check_warp, fit_composite, jacobian, pulled_back, z_units
from .warp import AUTO_WARPS, ESCALATE, ESCALATE_WARPS


class Fit:
    """The learned state of one fit: attributes named as CDSP's learned attributes (``C_``, ...)."""

    def __init__(self, **state):
        self.__dict__.update(state)

    def field(self, X, goal):
        """xdot at the rows of X for ``goal`` (:func:`field_at`)."""
        return field_at(X, goal, self.scale_, self.mixture_, self.C_, self.field_exps_, self.warp_,
                        getattr(self, "floor_", None))


def fit(demos: Demonstrations, params: dict, progress=None, t_start: float | None = None) -> Fit:
    """The whole fit path (module docstring) for checked ``demos`` and ``params`` (CDSP's)."""
    t_start = time.perf_counter() if t_start is None else t_start
    params = dict(params, random_state=resolve_seed(params["random_state"]))
    if params["warp"] != "auto":
        if params["speed_floor"] == "auto":
            floor_steps(demos)          # the floor's choosing rollouts' size, checked before any fit
        core = fit_core(demos, warp_maps(demos, warp_settings(params["warp"])), params, progress, t_start)
        return with_floor(Fit(**vars(core), warp_scores_={}), demos, params["speed_floor"])
    score_steps(demos)                  # the scoring rollouts' size, checked before any fit
    if params["speed_floor"] == "auto":
        floor_steps(demos)
    spent = {"candidates_s": 0.0, "choice_s": 0.0}

    def timed(key, step, *args):
        t0 = time.perf_counter()
        out = step(*args)
        spent[key] += time.perf_counter() - t0
        return out

    fits = timed("candidates_s", candidate_fits, demos, {"none": None, **AUTO_WARPS}, params, progress)
    kept, scores = timed("choice_s", warp_choice, fits, demos, block_field)
    if min(v for name, v in scores.items() if fits[name] is kept) > ESCALATE * diagonal(demos):
        fits.update(timed("candidates_s", candidate_fits, demos, ESCALATE_WARPS, params, progress))
        kept, scores = timed("choice_s", warp_choice, fits, demos, block_field)
    out = with_floor(Fit(**dict(vars(kept), warp_scores_=scores)), demos, params["speed_floor"])
    out.timings_ = dict(kept.timings_, total_s=time.perf_counter() - t_start, **spent)
    return out


def with_floor(fitted: Fit, demos: Demonstrations, setting) -> Fit:
    """``fitted`` with its speed floor (:mod:`.floor`): none for "none", the rate ``setting`` for a
    number, or for "auto" :func:`~.floor.floor_choice` on the training demonstrations."""
    arrivals = {}
    if setting == "auto":
        rate, arrivals = floor_choice(lambda X: fitted.field(X, fitted.goal_), fitted.goal_, demos)
    else:
        rate = None if setting == "none" else float(setting)
    fitted.floor_ = None if rate is None else {"rate": rate, "boost": BOOST}
    fitted.floor_arrivals_ = arrivals
    return fitted


def diagonal(demos: Demonstrations) -> float:
    """The diagonal of the demonstrations' bounding box (data units)."""
    X = demos.stacked()[0]
    return float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))


def warp_maps(demos: Demonstrations, settings: dict | None):
    """The warp (bumps, twist or None; data units, :func:`~.composite.fit_composite`) fitted with
    ``settings`` (None: no warp)."""
    return None if settings is None else fit_composite([(d.t, d.pos) for d in demos], demos.goal, settings)


def candidate_fits(demos: Demonstrations, candidates: dict, params: dict, progress) -> dict:
    """{name: Fit or None} for ``candidates`` {name: warp settings or None}: one core fit per
    distinct warp (candidates whose greedy fits give equal bumps share it); None for a warped
    candidate that does not certify (the plain one must: its NotCertifiedError propagates)."""
    fitted, fits = {}, {}
    for name, settings in candidates.items():
        maps = warp_maps(demos, settings)
        key = None if maps is None else b"".join(np.ascontiguousarray(a).tobytes()
                                                 for a in (*maps[0], *(maps[1] or ())))
        if key not in fitted:
            try:
                fitted[key] = fit_core(demos, maps, params, tagged(progress, warp=name), time.perf_counter())
            except NotCertifiedError:
                if settings is None:
                    raise
                fitted[key] = None
        fits[name] = fitted[key]
    return fits


def fit_core(demos: Demonstrations, maps, params: dict, progress, t_start: float) -> Fit:
    """One fit through the warp ``maps`` (data units, or None): plain, or with corrective rounds
    (:func:`~.rounds.corrective_fits`; the kept round's state, every round's history rows)."""
    if params["corrective_rounds"] == 0:
        return Fit(**vars(fit_plain(demos, maps, params, progress, t_start)),
                   corrective_round_=0, corrective_scores_=[], corrective_pairs_=[])

    def fit_round(r, data):
        return fit_plain(data, maps, dict(params, corrective_rounds=0), tagged(progress, round=r),
                         time.perf_counter())

    r, kept, scores, pairs, history = corrective_fits(fit_round, demos, params["corrective_rounds"],
                                                      params["corrective_tau"], params["corrective_min_dist"])
    return Fit(**dict(vars(kept), corrective_round_=r, corrective_scores_=scores, corrective_pairs_=pairs,
                      history_=history, dt_=sample_step(demos),
                      timings_=dict(kept.timings_, total_s=time.perf_counter() - t_start)))


def fit_plain(demos: Demonstrations, maps, params: dict, progress, t_start: float) -> Fit:
    """One fit of the mixture, the fields and the metric, then the certificate and its check
    (NotCertifiedError if it fails, unless ``allow_uncertified``: then a warning), in u = phi(z)
    through the warp ``maps`` (data units; stored in z-units as ``warp_``, None without bumps)."""
    s, seed = Settings.from_params(params), params["random_state"]
    goal, scale, Z, Zdot = scaled_data(demos, params["n_components"], params["max_samples"])
    warp = z_units(maps, goal, scale)
    U, Udot = warped_data(Z, Zdot, warp)
    history, timings = History(progress), {}

    t0 = time.perf_counter()
    gmm, bic = fit_joint_gmm(U, Udot, params["n_components"], seed)
    mixture = PositionMixture.from_joint(gmm, demos.dim)
    timings["em_s"] = time.perf_counter() - t0
    fexps, mexps = field_exponents(demos.dim, s.field_degree), metric_exponents(demos.dim, s.learned_metric_degree)

    t0 = time.perf_counter()
    C, W, mixture_ = learn(U, Udot, mixture, s, history)
    if params["gating"] != "posterior":                             # tempered off the training points
        mixture_ = with_bound(mixture_, gate_bound(mixture_, U), FADE if params["gating"] == "smooth" else None)
    timings["learn_s"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    certificate = extract_certificate(certify(C, fexps, W, mexps, s.gamma, 0.5 * s.eps, s.solver), 0.5 * s.eps)
    timings["certify_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    verification = check_fit(C, fexps, W, mexps, s.gamma, certificate, warp, params["verify_samples"], seed)
    timings["verify_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - t_start
    state = Fit(seed_=seed, dim_=demos.dim, goal_=goal, scale_=scale, dt_=sample_step(demos), units_=demos.units,
                columns_=demos.columns,
                warp_=warp, history_=history.rows, timings_=timings, n_components_=gmm.n_components,
                mixture_=mixture_, field_exps_=fexps, metric_exps_=mexps, gmr_cost_=gmr_cost(gmm, U, Udot),
                C_=C, W_=W, certificate_=certificate, verification_=verification,
                metric_collapse_=collapse_diagnostic(C, fexps, W, mexps, s.gamma, seed),
                certified_=verification.passed, **({} if bic is None else {"bic_": bic}))
    if not state.certified_:
        msg = f"the learned model's certificate failed its independent check:\n{verification}"
        if not params["allow_uncertified"]:
            raise NotCertifiedError(msg, "solver_error", "a smaller gamma, a larger margin, or "
                                    "solver='SCS'; or pass allow_uncertified=True to inspect it")
        warnings.warn(msg, stacklevel=2)
    return state


def scaled_data(demos: Demonstrations, n_components, max_samples):
    """(goal x*, scale s, Z, Zdot): the samples (subsampled to ``max_samples``) as z = (x - x*)/s,
    zdot = xdot/s, s the largest |x_c - x*_c| (1 if 0); InputError if fewer than
    MIN_SAMPLES_PER_COMPONENT per Gaussian remain."""
    K = 1 if n_components == "bic" else int(n_components)
    X, Xdot, subsampled = subsample(*demos.stacked(), max_samples)
    if X.shape[0] < MIN_SAMPLES_PER_COMPONENT * K:
        raise InputError(f"{X.shape[0]} samples{' (after max_samples)' if subsampled else ''} are "
                         f"too few for {K} Gaussians; use fewer components, more demonstrations"
                         f"{' or a larger max_samples' if subsampled else ''}")
    goal = np.asarray(demos.goal, dtype=float)
    scale = float(np.abs(X - goal).max()) or 1.0
    return goal, scale, (X - goal) / scale, Xdot / scale


def warped_data(Z, Zdot, warp):
    """(phi(z_i), J_phi(z_i) zdot_i) through the z-unit ``warp`` (the data itself for None)."""
    if warp is None:
        return Z, Zdot
    U, J = jacobian(Z, warp)
    return U, np.einsum("tij,tj->ti", J, Zdot)


def core_field(U, mixture: PositionMixture, C, fexps):
    """udot = sum_k h_k(u) f_k(u) at the rows of U (the certified system)."""
    return core_fields(U, [(mixture, C, fexps)])


def core_fields(U, models: list) -> np.ndarray:
    """:func:`core_field` of ``models[b]`` = (mixture, C, fexps) at the b-th of len(models) equal
    blocks of rows of U, the weights of all blocks in one pass (:func:`~.gmm.responsibilities_of`)."""
    rows = len(U) // len(models)
    blocks = [U[b * rows:(b + 1) * rows] for b in range(len(models))]
    H = responsibilities_of([mix for mix, _, _ in models], blocks)
    return np.vstack([np.einsum("tk,tki->ti", h, eval_fields(C, fexps, Ub))
                      for h, Ub, (_, C, fexps) in zip(H, blocks, models)])


def block_core(models: list, rows: int):
    """``core(U)``: :func:`core_fields` of ``models`` on blocks of ``rows`` rows, prepared once for
    many calls: when the models share K, n and the monomials, every row carries its model's
    mixture factors (:func:`~.gmm.block_log_joint`) and coefficients, so the log-joints, the fields
    and their weighted sum are one pass each over all rows (the same numbers as block by block)."""
    mixtures, fexps = [mix for mix, _, _ in models], models[0][2]
    if len({(mix.n_components, mix.means.shape[1]) for mix in mixtures}) > 1 or \
            not all(np.array_equal(f, fexps) for _, _, f in models):
        return lambda U: core_fields(U, models)
    log_joint, C = block_log_joint(mixtures, rows), np.repeat(np.array([C for _, C, _ in models]), rows, axis=0)

    def core(U):
        if not np.isfinite(U).all():
            return core_fields(U, models)           # responsibilities_of's InputError names the row
        L = log_joint(U)
        H = np.concatenate(weights_from([L[b * rows:(b + 1) * rows] for b in range(len(models))], mixtures,
                                        [U[b * rows:(b + 1) * rows] for b in range(len(models))]))
        return np.einsum("tk,tki->ti", H, np.einsum("tkij,tj->tki", C, monomial_values(U, fexps)))
    return core


def field_at(X, goal, scale, mixture, C, fexps, warp, floor=None):
    """xdot at the rows of X for ``goal`` (the field translated to it): s f(z), or through the warp
    s J_phi(z)^{-1} f(phi(z)), z = (x - goal) / s; with a speed ``floor`` ({"rate", "boost"}, and
    "radius" for a settle zone) times sigma(x) (:func:`~.floor.floored`)."""
    Z = (X - goal) / scale
    core = lambda U: core_field(U, mixture, C, fexps)       # noqa: E731
    V = (core(Z) if warp is None else pulled_back(Z, warp, core)) * scale
    return V if floor is None else floored(X - goal, V, *floor_terms(floor))


def block_field(fits: list):
    """``field(X, live)``: fit b's field (:func:`field_at`, at its own goal and speed floor) on the b-th
    block of equal consecutive rows of X, for b in ``live``; the blocks' warps evaluated together
    (:func:`~.composite.block_pull`, prepared once per set of live blocks):
    the same numbers as each fit's field on its block."""
    stacked = {}                    # per set of live blocks: (goal, scale, pull-back or None, core) of their rows

    def rows_of(live, rows, n):
        key = (tuple(live), rows)
        if key not in stacked:
            each = lambda a: np.repeat(np.array([a(fits[b]) for b in live], dtype=float), rows, axis=0)  # noqa: E731
            stacked[key] = (each(lambda f: f.goal_), each(lambda f: f.scale_)[:, None],
                            block_pull([fits[b].warp_ for b in live], rows, n),
                            block_core([(fits[b].mixture_, fits[b].C_, fits[b].field_exps_) for b in live], rows))
        return stacked[key]

    def field(X, live):
        rows = len(X) // len(live)
        goal, scale, pull, core = rows_of(live, rows, X.shape[1])
        Z = (X - goal) / scale
        V = (core(Z) if pull is None else pull(Z, core)) * scale
        floors = [getattr(fits[b], "floor_", None) for b in live]
        if all(f is None for f in floors):
            return V
        terms = np.array([(0.0, 1.0, np.inf) if f is None else floor_terms(f) for f in floors])
        rate, boost, radius = (np.repeat(terms[:, i], rows)[:, None] for i in range(3))
        return floored(X - goal, V, rate, boost, radius)
    return field


def check_fit(C, fexps, W, mexps, gamma, certificate, warp, n_samples: int, seed: int) -> CertificateReport:
    """The independent check: Gram matrices and the sampled contraction inequality
    (:func:`~.certificate.check_certificate`), and with a warp its own check (:func:`~.composite.check`)."""
    report = check_certificate(C, fexps, W, mexps, gamma, certificate, n_samples, seed)
    if warp is None:
        return report
    checked = check_warp(warp, n_samples, seed)
    return replace(report, warp=checked, passed=report.passed and checked["passed"])


def tagged(progress, **tag):
    """``progress`` with ``tag`` added to every row (None stays None)."""
    return None if progress is None else (lambda row: progress(dict(row, **tag)))


__all__ = ["Fit", "block_field", "with_floor", "candidate_fits", "check_fit", "core_field", "core_fields", "field_at", "fit", "fit_core", "fit_plain",
           "scaled_data", "tagged", "warp_maps", "warped_data"]

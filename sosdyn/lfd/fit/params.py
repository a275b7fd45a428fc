"""The CDSP hyper-parameters: their names, checks and the seed a fit uses.

Every parameter is checked before any optimisation (InputError saying what to try); a model
file's parameters go through the same checks. Numbers may be Python or numpy scalars
(np.float32, np.int64); booleans are not numbers here.
"""
from __future__ import annotations

from collections.abc import Mapping
from numbers import Integral, Real

import numpy as np

from sosdyn.errors import InputError
from sosdyn.sos import SOLVERS
from .certificate import check_sample_count
from .corrective import MIN_DIST, TAU
from .twist import MAX_SHEAR
from .warp import MATCHES, MAX_MAPS, TARGETS, WARP_DEFAULTS

METHODS = ("alternating", "ica")
METRICS = ("learned", "identity")
MAX_SEED = 2**32 - 1            # numpy's and sklearn's bound on an integer seed
MAX_CORRECTIVE_ROUNDS = 10      # corrective refits of one fit (each a whole CDSP fit)
PARAMS = ("n_components", "metric_degree", "field_degree", "gamma", "metric", "solver",
          "solver_method", "max_iter", "tol", "eps", "margin", "metric_prox", "refine_gmm", "max_samples",
          "random_state", "verify_samples", "allow_uncertified", "corrective_rounds", "corrective_tau",
          "corrective_min_dist", "warp", "gating", "speed_floor")     # what get_params and a file hold
GATINGS = ("posterior", "tempered", "smooth")   # the mixture weights: plain, or tempered off the data (.gmm)
WARPS = ("auto", "none")        # warp: one of these, or a dict of WARP_DEFAULTS' keys (one fixed warp)
FLOORS = ("auto", "none")       # speed_floor: one of these, or a rate kappa > 0 (1/s) (.floor)
MAX_POINTS = 10_000
CORRECTIVE_OFF = {"corrective_rounds": 0}     # no corrective refits
PLAIN = {**CORRECTIVE_OFF, "warp": "none", "speed_floor": "none"}    # one plain fit: no refits, warp or floor
#: Named configurations (``CDSP.preset(name)``): the parameters each sets, the rest default.
#: "paper": the paper's formulation as first implemented (K = 6 linear sub-systems, constant
#: metric, plain alternation with the max-margin metric step) -- the reproduction's base;
#: "ica": the same model learned by the inner convex approximation (CDSP() is "ica" with K = 8
#: and warp="auto", :mod:`.warp`);
#: "cubic": cubic sub-systems, degree-2 metric M(z), started from "ica", proximal alternation.
#: Every preset is one plain fit (PLAIN: no warp, no corrective refits, no speed floor; the configurations
#: as measured alone); ``CDSP.preset(name, warp="auto")`` adds the default's choice of warp.
PRESETS = {
    "paper": {"n_components": 6, "metric_degree": 0, "field_degree": 1, "gamma": 0.1,
              "solver_method": "alternating", "metric_prox": 0.0, **PLAIN},
    "ica": {"n_components": 6, "metric_degree": 0, "field_degree": 1, "gamma": 0.1, "solver_method": "ica",
            **PLAIN},
    "cubic": {"n_components": 6, "metric_degree": 2, "field_degree": 3, "gamma": 0.1, "solver_method": "ica",
              **PLAIN},
}
#: Parameters added after earlier model files were written, with the value those fits used
#: (tau and min_dist are unused at 0 rounds; recorded as the defaults).
LEGACY_PARAMS = {"metric_prox": 0.0, "corrective_rounds": 0, "corrective_tau": TAU, "corrective_min_dist": MIN_DIST,
                 "warp": "none", "gating": "posterior", "speed_floor": "none"}


def check_params(p: Mapping, defaults: Mapping) -> None:
    """Types and ranges of every parameter in ``p`` (PARAMS, and ``progress`` if present);
    ``defaults`` are suggested in the messages. No solver is touched (see :func:`check_solver`)."""
    def fail(name, want):
        raise InputError(f"{name} must be {want}, got {p[name]!r}. "
                         f"Try: the default, {name}={defaults[name]!r}.")

    def integer(name, lo):
        v = p[name]
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, Integral) or v < lo:
            fail(name, f"an integer >= {lo}")

    def positive(name):
        v = p[name]
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, Real) or not np.isfinite(v) or v <= 0:
            fail(name, "a positive finite number")

    def choice(name, options):
        if not isinstance(p[name], str) or p[name] not in options:
            fail(name, f"one of {options}")

    if not (isinstance(p["n_components"], str) and p["n_components"] == "bic"):
        if isinstance(p["n_components"], str):
            fail("n_components", 'an integer >= 1 or "bic"')
        integer("n_components", 1)
    integer("metric_degree", 0)
    integer("field_degree", 1)
    integer("max_iter", 0)
    integer("corrective_rounds", 0)
    if p["corrective_rounds"] > MAX_CORRECTIVE_ROUNDS:
        fail("corrective_rounds", f"at most {MAX_CORRECTIVE_ROUNDS} (each round is a whole refit)")
    if p["metric_degree"] % 2:
        raise InputError(f"metric_degree={p['metric_degree']} is odd: a polynomial metric of odd "
                         "degree cannot be positive definite for all x; use 0, 2 or 4")
    if p["field_degree"] % 2 == 0:
        raise InputError(
            f"field_degree={p['field_degree']} is even: the contraction condition then has odd "
            f"degree {p['metric_degree'] + p['field_degree'] - 1} in x and its leading part cannot "
            "be negative definite, so no certificate exists; use field_degree 1 or 3")
    for name in ("gamma", "eps", "tol", "margin"):
        positive(name)
    positive("corrective_tau")
    for name in ("metric_prox", "corrective_min_dist"):
        v = p[name]
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, Real) or not np.isfinite(v) or v < 0:
            fail(name, "a finite number >= 0")
    choice("metric", METRICS)
    choice("gating", GATINGS)
    if not (isinstance(p["speed_floor"], str) and p["speed_floor"] in FLOORS):
        if isinstance(p["speed_floor"], (str, bool, np.bool_)) or not isinstance(p["speed_floor"], Real) \
                or not np.isfinite(p["speed_floor"]) or p["speed_floor"] <= 0:
            fail("speed_floor", f"one of {FLOORS} or a rate > 0 (1/s)")
    choice("solver_method", METHODS)
    if not isinstance(p["solver"], str) or not p["solver"]:
        fail("solver", f"the name of a conic solver, e.g. one of {SOLVERS}")
    if p["max_samples"] is not None:
        integer("max_samples", 1)
    check_sample_count(p["verify_samples"], "verify_samples")
    rs = p["random_state"]
    if not (rs is None or isinstance(rs, (np.random.Generator, np.random.RandomState))):
        if isinstance(rs, (bool, np.bool_)) or not isinstance(rs, Integral) or not 0 <= rs <= MAX_SEED:
            fail("random_state", f"None, an integer in [0, {MAX_SEED}], a np.random.Generator or a "
                 "np.random.RandomState")
    for name in ("refine_gmm", "allow_uncertified"):
        if not isinstance(p[name], (bool, np.bool_)):
            fail(name, "True or False")
    if p.get("progress") is not None and not callable(p["progress"]):
        fail("progress", "None or a function called with each history row")
    warp_settings(p["warp"])


def warp_settings(warp) -> dict | None:
    """The parameter ``warp`` checked: None for "auto" and "none", else the dict completed with
    WARP_DEFAULTS (InputError naming the bad key or value and what to try)."""
    if isinstance(warp, str) and warp in WARPS:
        return None
    if not isinstance(warp, Mapping):
        raise InputError(f"warp must be 'auto', 'none' or a dict of warp settings, got {warp!r:.60}. "
                         "Try: warp='auto' (the default), 'none', or e.g. {'n_maps': 60, 'decay': 1.0}.")
    unknown = sorted(set(warp) - set(WARP_DEFAULTS), key=str)
    if unknown:
        raise InputError(f"warp has unknown settings {unknown}. Try: keys among {tuple(WARP_DEFAULTS)}.")
    s = {**WARP_DEFAULTS, **warp}

    def bad(name, want):
        raise InputError(f"warp[{name!r}] must be {want}, got {s[name]!r:.40}. Try: "
                         f"{name}={WARP_DEFAULTS[name]!r} (the default).")

    def number(name):
        v = s[name]
        return not isinstance(v, (bool, np.bool_)) and isinstance(v, Real) and bool(np.isfinite(v))

    for name, lo, hi in (("n_maps", 0, MAX_MAPS), ("n_points", 10, MAX_POINTS)):
        v = s[name]
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, Integral) or not lo <= v <= hi:
            bad(name, f"an integer in [{lo}, {hi}]")
    if not (number("l_max") and 0 < s["l_max"] < 1):
        bad("l_max", "a number in (0, 1) (< 1 keeps every bump invertible)")
    if not (number("beta") and 0 < s["beta"] <= 1):
        bad("beta", "a number in (0, 1]")
    if not (number("decay") and 0 <= s["decay"] <= 1):
        bad("decay", "a number in [0, 1]")
    if not (number("twist") and 0 <= s["twist"] <= MAX_SHEAR):
        bad("twist", f"a number in [0, {MAX_SHEAR:g}] (the twist's shear bound K; 0: no twist)")
    if s["match"] not in MATCHES:
        bad("match", f"one of {MATCHES}")
    if s["target"] not in TARGETS:
        bad("target", f"one of {TARGETS}")
    return s


def preset_params(name: str) -> dict:
    """The parameters of the preset ``name`` (:data:`PRESETS`); InputError for an unknown name."""
    if not isinstance(name, str) or name not in PRESETS:
        raise InputError(f"unknown preset {name!r}. Try: one of {tuple(PRESETS)}.")
    return dict(PRESETS[name])


def check_solver(solver: str) -> None:
    """The solver is one sosdyn drives directly or one installed in cvxpy."""
    if solver.upper() in SOLVERS:
        return
    import cvxpy as cp  # lazy: importing cvxpy takes seconds; only other solvers need it
    installed = cp.installed_solvers()
    if solver.upper() not in installed:
        raise InputError(f"unknown solver {solver!r}; use one of {SOLVERS} or a conic solver "
                         f"installed in cvxpy ({', '.join(installed)}). Try: solver='CLARABEL'.")


def resolve_seed(random_state) -> int:
    """The integer seed a fit uses: the integer itself, one drawn from a Generator/RandomState
    (advancing it, as sklearn does), or a fresh one for None."""
    if isinstance(random_state, np.random.RandomState):
        return int(random_state.randint(0, MAX_SEED, dtype=np.int64))
    if random_state is None or isinstance(random_state, np.random.Generator):
        return int(np.random.default_rng(random_state).integers(0, MAX_SEED))
    return int(random_state)

"""The content of a model file: the parameters' names and the learned state, field by field.

:func:`validate_state` turns a file's ``state`` object into checked arrays (shapes implied by
the parameters, finite numbers, symmetric W, a valid mixture and certificate layout) or raises
a :class:`~sosdyn.errors.ModelFileError` naming the first bad field; :func:`state_record` is
the inverse for saving. The estimator is built from these values by :mod:`sosdyn.lfd.model.cdsp`.
"""
from __future__ import annotations

import math

import numpy as np

from sosdyn.errors import InputError, ModelFileError
from ..data.demonstrations import units_problem
from ..fit.contraction import field_exponents, metric_exponents
from ..fit.gmm import PositionMixture
from ..fit.composite import TWIST_KEYS
from ..fit.twist import check_twist
from ..fit.warp import check_maps

STATE_FIELDS = ("dim_", "goal_", "scale_", "dt_", "units_", "n_components_", "gmr_cost_", "C_", "W_",
                "field_exps_", "metric_exps_", "mixture_", "certificate_", "history_", "metric_collapse_",
                "timings_", "warp_")
WARP_KEYS = ("centers", "vectors", "sigmas")          # warp_: null, or these arrays (z-units) and an optional twist


def need(mapping: dict, name: str, where: str, kind=None):
    """mapping[name] (``where`` names the mapping; "" at the top), present and (if ``kind`` is
    given) of that JSON type."""
    full = f"{where}.{name}" if where else name
    if not isinstance(mapping, dict) or name not in mapping:
        raise ModelFileError(f"malformed: the field {full} is missing")
    v = mapping[name]
    if kind is not None and not isinstance(v, kind):
        raise ModelFileError(f"malformed: {full} is a {type(v).__name__}, expected a {kind.__name__}")
    return v


def integer(value, where: str, lo: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise ModelFileError(f"malformed: {where} must be an integer >= {lo}, got {value!r:.40}")
    return value


def positive(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise ModelFileError(f"malformed: {where} must be a positive number, got {value!r:.40}")
    return float(value)


def array(value, where: str, shape: tuple, dtype=float) -> np.ndarray:
    """``value`` (nested lists) as an array of exactly ``shape``: numbers (``dtype`` float) or
    non-negative integers (``dtype`` int). JSON true/false are not numbers here."""
    try:
        a = np.array(value, dtype=object)
    except ValueError:                       # ragged nesting numpy cannot even hold as objects
        a = np.empty(0, dtype=object)
    if a.shape != tuple(shape):
        raise ModelFileError(f"malformed: {where} must be an array of shape {tuple(shape)}, got "
                             f"{'shape ' + str(a.shape) if a.size else 'a ragged or empty nesting'}")
    kinds = (int,) if dtype is int else (int, float)
    if not all(type(v) in kinds for v in a.flat) or (dtype is int and not all(0 <= v < 2**31 for v in a.flat)):
        raise ModelFileError(f"malformed: {where} must hold "
                             f"{'non-negative integers (exponents)' if dtype is int else 'numbers'} only")
    return a.astype(np.int64 if dtype is int else float)


# ---------------------------------------------------------------------- the parameters and the state
def check_param_names(params: dict, names) -> None:
    """The file's parameters are exactly ``names``."""
    expected = set(names)
    if set(params) != expected:
        missing, unknown = sorted(expected - set(params)), sorted(set(params) - expected)
        raise ModelFileError(f"malformed: params {'lacks ' + str(missing) if missing else ''}"
                             f"{' and ' if missing and unknown else ''}"
                             f"{'has unknown ' + str(unknown) if unknown else ''}")


def state_record(state: dict) -> dict:
    """``state`` (STATE_FIELDS) as file content: the mixture as its three arrays."""
    m = state["mixture_"]
    return dict(state, mixture_={"weights": m.weights, "means": m.means, "covariances": m.covariances,
                                 "bound": m.bound})


def validate_state(st: dict, n_components, field_degree: int, metric_degree: int, eps: float) -> dict:
    """The checked STATE_FIELDS of a file's ``state`` for these (already checked) parameters:
    ``n_components`` (int or "bic"), the fields' degree, the metric's degree as learned (0 for
    the identity metric) and eps; the mixture as a PositionMixture."""
    out = {}
    n = out["dim_"] = integer(need(st, "dim_", "state"), "state.dim_", 1)
    K = out["n_components_"] = integer(need(st, "n_components_", "state"), "state.n_components_", 1)
    if n_components != "bic" and K != n_components:
        raise ModelFileError(f"malformed: state.n_components_ = {K} but params.n_components = "
                             f"{n_components}")
    F, D = field_degree, metric_degree
    fexps = out["field_exps_"] = _exponents(st, "field_exps_", n, math.comb(n + F, F) - 1,
                                            lambda: field_exponents(n, F))
    mexps = out["metric_exps_"] = _exponents(st, "metric_exps_", n, math.comb(n + D, D),
                                             lambda: metric_exponents(n, D))
    out["goal_"] = array(need(st, "goal_", "state"), "state.goal_", (n,))
    out["scale_"] = positive(need(st, "scale_", "state"), "state.scale_")
    out["dt_"] = positive(need(st, "dt_", "state"), "state.dt_")
    out["units_"] = units = need(st, "units_", "state")
    if units_problem(units):
        raise ModelFileError(f"malformed: state.units_ {units_problem(units)}")
    out["gmr_cost_"] = float(array(need(st, "gmr_cost_", "state"), "state.gmr_cost_", ()))
    out["C_"] = array(need(st, "C_", "state"), "state.C_", (K, n, len(fexps)))
    W = out["W_"] = array(need(st, "W_", "state"), "state.W_", (n, n, len(mexps)))
    if not np.array_equal(W, W.transpose(1, 0, 2)):
        raise ModelFileError("malformed: state.W_ is not symmetric in its first two axes, so M(z) "
                             "would not be a symmetric matrix")
    out["mixture_"] = _mixture(need(st, "mixture_", "state", dict), K, n)
    out["certificate_"] = _certificate(need(st, "certificate_", "state", dict), K, eps)
    history = out["history_"] = need(st, "history_", "state", list)
    if not all(isinstance(row, dict) for row in history):
        raise ModelFileError("malformed: state.history_ must be a list of objects")
    out["timings_"] = need(st, "timings_", "state", dict)
    collapse = out["metric_collapse_"] = need(st, "metric_collapse_", "state")
    if not (collapse is None or isinstance(collapse, dict)):
        raise ModelFileError("malformed: state.metric_collapse_ must be null or an object")
    out["warp_"] = _warp(st.get("warp_"), n)              # absent in files older than the warp: none
    unknown = sorted(set(st) - set(STATE_FIELDS))
    if unknown:
        raise ModelFileError(f"malformed: state has unknown fields {unknown}")
    return out


def _warp(w, n) -> dict | None:
    """None, or {centers (m, n), vectors (m, n), sigmas (m,)}: finite, sigma_j > 0, every l_j < 1;
    and, if present, twist {plane (2, n) orthonormal, amplitudes (k,), widths (k,) > 0}
    (:func:`~sosdyn.lfd.fit.twist.check_twist`). A file older than the twist has none."""
    if w is None:
        return None
    if not isinstance(w, dict) or not set(WARP_KEYS) <= set(w) <= {*WARP_KEYS, "twist"}:
        raise ModelFileError(f"malformed: state.warp_ must be null or an object with exactly {list(WARP_KEYS)} "
                             "and optionally twist")
    sigmas = need(w, "sigmas", "state.warp_", list)
    m = len(sigmas)
    out = {"sigmas": array(sigmas, "state.warp_.sigmas", (m,))}
    for key in ("centers", "vectors"):
        v = need(w, key, "state.warp_")
        out[key] = np.zeros((0, n)) if m == 0 and v == [] else array(v, f"state.warp_.{key}", (m, n))  # no bump: []
    try:
        check_maps(out["centers"], out["vectors"], out["sigmas"], np.zeros(n), what="state.warp_")
    except InputError as exc:
        raise ModelFileError(f"invalid {exc}") from None
    t = w.get("twist")
    if t is None:
        return out
    if not isinstance(t, dict) or set(t) != set(TWIST_KEYS):
        raise ModelFileError(f"malformed: state.warp_.twist must be an object with exactly {list(TWIST_KEYS)}")
    k = len(need(t, "widths", "state.warp_.twist", list))
    twist = {"plane": array(need(t, "plane", "state.warp_.twist"), "state.warp_.twist.plane", (2, n)),
             **{key: array(need(t, key, "state.warp_.twist"), f"state.warp_.twist.{key}", (k,))
                for key in ("amplitudes", "widths")}}
    try:
        check_twist(twist["plane"], twist["amplitudes"], twist["widths"], what="state.warp_.twist")
    except InputError as exc:
        raise ModelFileError(f"invalid {exc}") from None
    return dict(out, twist=twist)


def _exponents(st, name, n, count, expected):
    """The exponent rows of ``name``: ``count`` distinct rows, the library's monomial set."""
    exps = array(need(st, name, "state"), f"state.{name}", (count, n), dtype=int)
    if not np.array_equal(np.unique(exps, axis=0), np.unique(expected(), axis=0)) \
            or len(np.unique(exps, axis=0)) != count:
        raise ModelFileError(f"malformed: state.{name} are not the monomials the parameters imply "
                             f"({count} distinct exponent rows in {n} variables)")
    return exps


def _mixture(mx, K, n) -> PositionMixture:
    """Weights > 0 summing to 1, means (K, n), covariances (K, n, n) symmetric positive definite,
    the gating's bound null or a positive number (absent in files older than it: null, the plain
    posterior, so such a model evaluates as it did)."""
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
    bound = mx.get("bound")
    unknown = sorted(set(mx) - {"weights", "means", "covariances", "bound"})
    if unknown:
        raise ModelFileError(f"malformed: state.mixture_ has unknown fields {unknown}")
    return PositionMixture(w, means, cov, None if bound is None else positive(bound, "state.mixture_.bound"))


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

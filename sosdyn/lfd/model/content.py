"""The content of the model files of all three families, and every check of it: the one place a
file's fields are validated (:mod:`.fileformat` holds the container: size, JSON, digests).

A file is one JSON object: ``format``, ``version`` and the family's fields (:data:`TOP_LEVEL`);
anything else is refused, naming the field (:func:`check_fields`). Each field is read by the
helpers here -- :func:`need`, :func:`integer`, :func:`positive`, :func:`array` -- which accept
finite JSON numbers only where a number is required (a JSON ``null`` is not a number: it never
becomes NaN) and raise a :class:`~sosdyn.errors.ModelFileError` naming the field.

Work is bounded before it starts (:func:`check_load_work`): the dimension n and the components K
are read from the file's header fields first and compared with ``max_model_dim`` and
``max_model_components``; a second-order file's exact certificate check costs about
(K + 1)(2n)^3 rational multiply-adds (K + 1 exact LDL^T of 2n x 2n matrices), compared with
``max_exact_work``; a first-order (or pose) file's sampled check costs about S K n^2 (m + p)
multiply-adds (S = DEFAULT_SAMPLES states, or 1 for linear fields under a constant metric, whose
matrices do not depend on the state; m field and p metric monomials), compared with
``max_sampled_work`` (:mod:`sosdyn.limits`). So a file the limits admit loads in seconds (measured:
a 24-D 3-component and a 16-D 14-component second-order file at the limit, 3.3 and 4.0 s).

Per family: the first-order state (:func:`validate_state`, also each of the pose model's two blocks;
:func:`state_record` is the inverse for saving), the second-order state
(:func:`second_order_state`) and the pose model's own fields (:func:`pose_fields`). The estimators
are built from the checked values by their ``from_content`` (:mod:`.cdsp`, :mod:`.pose`,
:mod:`.second_order`).
"""
from __future__ import annotations

import math

import numpy as np

from sosdyn.errors import InputError, ModelFileError
from sosdyn.limits import check_count
from ..data.demonstrations import check_columns, units_problem
from ..fit.certificate import DEFAULT_SAMPLES
from ..fit.contraction import field_exponents, metric_exponents
from ..fit.gmm import PositionMixture
from ..fit.composite import TWIST_KEYS
from ..fit.twist import check_twist
from ..fit.warp import check_maps
from .fileformat import FORMAT

POSE_FORMAT, POSE_VERSION = "sosdyn-pose", 2
BLOCKS = ("position", "orientation")         # a pose file's two CDSP blocks (params and state each)
SECOND_ORDER_FORMAT, SECOND_ORDER_VERSION = "sosdyn-second-order", 1
#: Each format's top-level fields besides ``format`` and ``version`` (the digests are the container's).
TOP_LEVEL = {FORMAT: ("params", "state"), SECOND_ORDER_FORMAT: ("params", "state"),
             POSE_FORMAT: ("goal_tol_deg", "goal_quat", "still", *BLOCKS)}
SECOND_ORDER_STATE = ("goal", "dt", "length_scale", "time_scale", "window", "C", "M", "margin")
#: A second-order state's own fields by its ``field`` parameter: the gating mixture, or the tracked samples and the tank.
SECOND_ORDER_OWN = {"mixture": ("weights", "means", "covariances"),
                    "tracking": ("samples", "sample_accelerations", "beta")}
OPTIONAL_STATE = ("units", "columns")     # absent in files older than them: "" and unnamed
STATE_FIELDS = ("dim_", "goal_", "scale_", "dt_", "units_", "columns_", "n_components_", "gmr_cost_", "C_", "W_",
                "field_exps_", "metric_exps_", "mixture_", "certificate_", "history_", "metric_collapse_",
                "timings_", "warp_", "floor_")
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


def check_fields(mapping: dict, allowed, where: str) -> None:
    """Every key of ``mapping`` is one of ``allowed``: an unknown field is refused, named."""
    unknown = sorted(set(mapping) - set(allowed))
    if unknown:
        full = f"{where}.{unknown[0]}" if where else unknown[0]
        raise ModelFileError(f"malformed: unknown field {full} (a {where or 'file'} holds exactly "
                             f"{', '.join(sorted(allowed))})")


def labels(units, columns, dim: int, units_field: str, columns_field: str) -> tuple[str, tuple | None]:
    """The units' name and the ``dim`` position columns' names (None: unnamed) of the fields named so."""
    if units_problem(units):
        raise ModelFileError(f"malformed: {units_field} {units_problem(units)}")
    try:
        return units, check_columns(columns, dim)
    except InputError as exc:
        raise ModelFileError(f"malformed: {columns_field}: {exc}") from None


# ---------------------------------------------------------------------- the work a load will do
def check_load_work(fmt: str, content: dict) -> None:
    """ResourceLimitError (naming the limit and how to raise it) when the file's dimension, its
    components or, for a second-order file, its exact check's work (K + 1)(2n)^3 exceed the limits
    in force; read from the header fields before any other field is converted or checked."""
    if fmt == POSE_FORMAT:                       # two first-order blocks
        for block in BLOCKS:
            check_fields(need(content, block, "", dict), TOP_LEVEL[FORMAT], block)
            check_load_work(FORMAT, content[block])
        return
    state = need(content, "state", "", dict)
    if fmt == SECOND_ORDER_FORMAT:
        n, K = len(need(state, "goal", "state", list)), len(need(state, "C", "state", list))
    else:
        n = integer(need(state, "dim_", "state"), "state.dim_", 1)
        K = integer(need(state, "n_components_", "state"), "state.n_components_", 1)
    hint = "check it is the right file"
    check_count(n, "max_model_dim", "the model file's dimension n", hint)
    check_count(K, "max_model_components", "the model file's number of components K", hint)
    if fmt == SECOND_ORDER_FORMAT:
        check_count((K + 1) * (2 * n) ** 3, "max_exact_work", f"the exact check of its certificate "
                    f"(K + 1 = {K + 1} exact LDL^T of {2 * n} x {2 * n} rational matrices), (K + 1)(2n)^3", hint)
        N = len(state.get("samples", []) if isinstance(state.get("samples"), list) else [])
        check_count(2 * DEFAULT_SAMPLES * N * 2 * n, "max_sampled_work", f"the sampled check of its tank ("
                    f"{2 * DEFAULT_SAMPLES} states x {N} tracked samples of {2 * n} numbers), 2 S N 2n", hint)
        return
    params = need(content, "params", "", dict)
    F = integer(need(params, "field_degree", "params"), "params.field_degree", 1)
    D = 0 if params.get("metric") == "identity" else integer(need(params, "metric_degree", "params"),
                                                             "params.metric_degree")
    samples = 1 if F == 1 and D == 0 else DEFAULT_SAMPLES
    work = samples * K * n * n * (math.comb(n + F, F) - 1 + math.comb(n + D, D))
    check_count(work, "max_sampled_work", f"the sampled check of its certificate ({samples} states, K = {K}, "
                f"n = {n}, degrees {F} and {D}), S K n^2 (m + p)", hint)


# ---------------------------------------------------------------------- the first-order parameters and state
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
                                 "bound": m.bound, "fade": m.fade})


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
    out["units_"], out["columns_"] = labels(need(st, "units_", "state"), st.get("columns_"), n,
                                             "state.units_", "state.columns_")
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
    out["floor_"] = _floor(st.get("floor_"))              # absent in files older than the speed floor: none
    check_fields(st, STATE_FIELDS, "state")
    return out


def _floor(f) -> dict | None:
    """None, or the speed floor {"rate": kappa > 0 (1/s), "boost": B >= 1} and, for a settle zone,
    "radius": rho > 0 (data units; :mod:`~sosdyn.lfd.fit.floor`)."""
    if f is None:
        return None
    if not isinstance(f, dict) or not {"rate", "boost"} <= set(f) <= {"rate", "boost", "radius"}:
        raise ModelFileError('malformed: state.floor_ must be null or an object with "rate", "boost" and optionally '
                             '"radius"')
    rate, boost = positive(f["rate"], "state.floor_.rate"), positive(f["boost"], "state.floor_.boost")
    if boost < 1:
        raise ModelFileError(f"malformed: state.floor_.boost must be >= 1 (the floor never slows the field), got {boost!r}")
    return {"rate": rate, "boost": boost, **({"radius": positive(f["radius"], "state.floor_.radius")} if "radius" in f else {})}


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


def _mixture(mx, K, n, where: str = "state.mixture_") -> PositionMixture:
    """Weights > 0 summing to 1, means (K, n), covariances (K, n, n) symmetric positive definite,
    the gating's bound null or a positive number (absent in files older than it: null, the plain
    posterior, so such a model evaluates as it did) and its fade null or a positive number (absent in
    files older than it: null, no fade)."""
    w = array(need(mx, "weights", where), f"{where}.weights", (K,))
    means = array(need(mx, "means", where), f"{where}.means", (K, n))
    cov = array(need(mx, "covariances", where), f"{where}.covariances", (K, n, n))
    if not (w > 0).all() or abs(w.sum() - 1.0) > 1e-9:
        raise ModelFileError(f"malformed: {where}.weights must be positive and sum to 1, got "
                             f"{np.array2string(w, precision=4)} (sum {w.sum():.12g})")
    for k in range(K):
        S = cov[k]
        if np.abs(S - S.T).max() > 1e-12 * max(1.0, np.abs(S).max()):
            raise ModelFileError(f"malformed: {where}.covariances[{k}] is not symmetric")
        try:
            np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            raise ModelFileError(f"malformed: {where}.covariances[{k}] is not positive definite "
                                 "(no Cholesky factor)") from None
    bound, fade = mx.get("bound"), mx.get("fade")
    check_fields(mx, ("weights", "means", "covariances", "bound", "fade"), where)
    return PositionMixture(w, means, cov, None if bound is None else positive(bound, f"{where}.bound"),
                           None if fade is None else positive(fade, f"{where}.fade"))


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


# ---------------------------------------------------------------------- the second-order state
def second_order_state(st: dict, field: str = "mixture") -> dict:
    """The checked fields of a second-order file's ``state``: goal (n,), C (K, n, 2n), M (2n, 2n), dt,
    length_scale, time_scale and margin > 0, window an integer >= 1, units and columns; for the
    ``field`` "mixture" the gating mixture on e (weights > 0, means (K, 2n), covariances (K, 2n, 2n)
    symmetric positive definite), for "tracking" (K = 1) the tracked samples (N, 2n), their
    accelerations (N, n) and the tank factor beta >= 0."""
    check_fields(st, SECOND_ORDER_STATE + SECOND_ORDER_OWN[field] + OPTIONAL_STATE, "state")
    goal = need(st, "goal", "state", list)
    n = len(goal)
    K = len(need(st, "C", "state", list))
    out = {"goal": array(goal, "state.goal", (n,)), "C": array(st["C"], "state.C", (K, n, 2 * n)),
           "M": array(need(st, "M", "state"), "state.M", (2 * n, 2 * n))}
    for name in ("dt", "length_scale", "time_scale", "margin"):
        out[name] = positive(need(st, name, "state"), f"state.{name}")
    out["window"] = integer(need(st, "window", "state"), "state.window", 1)
    out["units"], out["columns"] = labels(st.get("units", ""), st.get("columns"), n, "state.units", "state.columns")
    if field == "mixture":
        out["mixture"] = _mixture({"weights": need(st, "weights", "state"), "means": need(st, "means", "state"),
                                   "covariances": need(st, "covariances", "state")}, K, 2 * n, "state")
    else:
        N = len(need(st, "samples", "state", list))
        if K != 1 or N < 1:
            raise ModelFileError(f"malformed: a tracking state holds one witness field (state.C has {K}) and at "
                                 f"least one sample (state.samples has {N})")
        out["samples"] = array(st["samples"], "state.samples", (N, 2 * n))
        out["sample_accelerations"] = array(need(st, "sample_accelerations", "state"), "state.sample_accelerations",
                                            (N, n))
        beta = need(st, "beta", "state")
        if isinstance(beta, bool) or not isinstance(beta, (int, float)) or not beta >= 0:
            raise ModelFileError(f"malformed: state.beta must be a number >= 0, got {beta!r:.40}")
        out["beta"] = float(beta)
    if n < 1 or K < 1:
        raise ModelFileError("malformed: state.goal and state.C must not be empty")
    return out


# ---------------------------------------------------------------------- the pose model's own fields
def pose_fields(content: dict) -> tuple[np.ndarray, dict, float]:
    """(goal_quat, still, goal_tol_deg) of a pose file: a unit quaternion (norm 1 to 1e-9; kept as stored, so a
    model and its reloaded copy hold the same numbers, and every use goes through scipy's Rotation, which
    normalises), the still rates
    ({"position", "orientation"}: null or a number > 0) and a tolerance in (0, 180) degrees, all finite
    numbers; each block (``position``, ``orientation``) must be an object of a first-order file's fields."""
    q = array(need(content, "goal_quat", ""), "goal_quat", (4,))
    if abs(np.linalg.norm(q) - 1) > 1e-9:
        raise ModelFileError(f"malformed: goal_quat must be a unit quaternion (norm 1), got norm {np.linalg.norm(q):.12g}")
    still = need(content, "still", "", dict)
    check_fields(still, BLOCKS, "still")
    rates = {b: None if need(still, b, "still") is None else positive(still[b], f"still.{b}") for b in BLOCKS}
    tol = positive(need(content, "goal_tol_deg", ""), "goal_tol_deg")
    if not tol < 180:
        raise ModelFileError(f"malformed: goal_tol_deg must be in (0, 180), got {tol!r}")
    for block in BLOCKS:
        check_fields(need(content, block, "", dict), TOP_LEVEL[FORMAT], block)
    return q, rates, tol

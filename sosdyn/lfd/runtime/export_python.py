"""Code generation: a fitted CDSP as a standalone evaluator (Python + numpy, or header-only C++17).

The generated code computes what :meth:`sosdyn.lfd.model.cdsp.CDSP.predict` computes, with every
number of the model written out in full precision (``repr`` of a float round-trips exactly):

    z = (x - x*) / s,    xdot = s * sum_k h_k(z) f_k(z),    f_k,i(z) = sum_j C[k, i, j] z^e_j

    q_k(z) = |L_k^-1 (z - mu_k)|^2  (S_k = L_k L_k^T),   tau(z) = max(1, min_k q_k / c)
    l_k(z) = log pi_k - sum_i log L_k,ii - n/2 log 2 pi - 1/2 q_k(z) / tau(z)
    h_k(z) = exp(l_k - logsumexp_i l_i)

(tau = 1 for a model without a gating bound c, :mod:`~sosdyn.lfd.fit.gmm`) and, where a quadratic
form overflows (|z| ~ 1e154 and up), :meth:`~sosdyn.lfd.fit.gmm.PositionMixture.far_weights`: h
one-hot on the component of least Mahalanobis distance, or with a bound c the softmax of
l_k = c_k - c/2 (d_k / d_min)^2, the distances from the rescaling of
:meth:`~sosdyn.lfd.fit.gmm.PositionMixture.log_mahalanobis`. A warped model (``warp_``, :mod:`.warp`)
evaluates the same sum at u = phi(z) and returns s J_phi(z)^-1 (...): the bump maps and their
chain-rule Jacobian (and a twist's, :mod:`~sosdyn.lfd.fit.twist`), then one n x n solve (numpy's, or Gaussian elimination with partial pivoting
in the C++). The generated code never imports
sosdyn: it is meant to run on a robot that has numpy (Python) or a C++17 compiler only.

One state (``predict(x)`` with x a finite float array of shape (n,)): the Python module runs the
predictor's plain-float arithmetic (:mod:`.predictor`: its functions' source is embedded, with
its tables as literals), the batch path for anything else and where a quadratic form overflows.

No text from the model reaches a generated file unescaped: the opening comment is fixed text and
numbers (so the first two lines of a Python module are never an encoding declaration), the units'
name is a Python literal written by ``ascii()`` or a C++ literal written by :func:`cpp_string`,
the C++ namespace an ASCII identifier.

Run-time goal: ``predict(X, goal=None)`` / ``predict(x, xdot, goal = nullptr)`` evaluate the
field with the goal moved to ``goal`` (z = (x - goal) / s; the goal-shifted model translated,
as a rollout's goal change does). Speed floor (the model's ``floor_``, :mod:`~sosdyn.lfd.fit.floor`):
xdot scaled by min(B, max(1, kappa |x - goal| / |xdot|)). Speed limit (``max_speed``, written into the
code, applied after the floor): the functions of :mod:`.states` (source embedded), the same smooth
positive factor as every other path.
"""
from __future__ import annotations

import inspect
import math

import numpy as np

from ..fit.floor import BOOST, fade, floor_terms, floored
from .codegen import MIXTURE_PY, RESPONSIBILITIES_PY, _check, _header, _literal, _twist, _warp, gating_py
from .predictor import (_monomial, field2, fieldn, floor_factor, gating, tables, twist_back, twist_forward, twist_tables, warp_back,
                        warp_back2, warp_forward, warp_forward2, warp_tables)
from .states import (SPEED_KNEE, check_max_speed, joint_ratio, limit_speed, limit_speed_one, saturated_speed,
                     saturated_speeds, saturation_factor, speed_ratio)


#: The speed limit's functions (:mod:`.states`, source embedded; the generated module defines SPEED_KNEE):
#: one state in plain floats, arrays, and the joint factor of two limits (the pose export).
SPEED_LIMIT_PY = "\n\n".join(inspect.getsource(f) for f in (saturated_speed, limit_speed_one, speed_ratio, saturated_speeds,
                                                           saturation_factor, limit_speed, joint_ratio))


#: The speed floor's functions on arrays (:mod:`~sosdyn.lfd.fit.floor`, source embedded).
FLOOR_PY = "\n\n".join(inspect.getsource(f) for f in (fade, floored))


def _floor_literal(floor) -> str:
    """FLOOR's literal: None, (rate, boost), or (rate, boost, radius) for a settle zone."""
    if floor is None:
        return "None"
    rate, boost, radius = floor_terms(floor)
    return repr((rate, boost) if math.isinf(radius) else (rate, boost, radius))


def to_python(model, max_speed: float | None = None) -> str:
    """Source of a standalone Python module (numpy only) with ``predict(X, goal=None) -> ndarray``:
    X of shape (m, n) gives (m, n), X of shape (n,) gives (n,); ``goal`` (n,) moves the goal;
    with ``max_speed`` every velocity is scaled to |xdot| <= max_speed."""
    _check(model)
    max_speed = check_max_speed(max_speed)
    mix, warp, twist = model.mixture_, _warp(model), _twist(model)
    warp_defs = "" if warp is None else f'''
# the warp u = phi(z), z-units: phi = psi_m o ... o psi_1, psi_j(z) = z + (rho_j(z) - rho_j(0)) v_j,
# rho_j(z) = exp(-|z - c_j|^2 / sigma_j^2)
WARP_CENTERS = np.array({_literal(warp[0])}).reshape(-1, {model.dim_})
WARP_VECTORS = np.array({_literal(warp[1])}).reshape(-1, {model.dim_})
WARP_SIGMAS = np.array({_literal(warp[2])}, dtype=float)


def warp(Z):
    """(phi(Z), J_phi(Z)) at the rows of Z: (N, n) and (N, n, n), by the chain rule."""
    U = np.array(Z, dtype=float)
    J = np.broadcast_to(np.eye(U.shape[1]), (U.shape[0],) + (U.shape[1],) * 2).copy()
    for c, v, s in zip(WARP_CENTERS, WARP_VECTORS, WARP_SIGMAS):
        rho = np.exp(-np.sum((U - c) ** 2, axis=-1) / s ** 2)
        grad = (-2.0 / s ** 2) * rho[:, None] * (U - c)
        J += v[None, :, None] * np.einsum("ki,kij->kj", grad, J)[:, None, :]
        U += (rho - np.exp(-np.sum((0.0 - c) ** 2) / s ** 2))[:, None] * v
    return {"U, J" if twist is None else "twist(U, J)"}
''' + ("" if twist is None else f'''

# then the twist u = R(alpha(|w|)) w, a rotation in the plane (p, q) = TWIST_PLANE by
# alpha(r) = sum_j a_j (1 - exp(-r^2 / tau_j^2)); J_T = R (I + beta (S w) w^T), beta = alpha'(r) / r
TWIST_PLANE = np.array({_literal(twist[0])}).reshape(2, {model.dim_})
TWIST_AMPLITUDES = np.array({_literal(twist[1])}, dtype=float)
TWIST_WIDTHS = np.array({_literal(twist[2])}, dtype=float)


def twist(W, JW):
    """(T(W), J_T(W) JW) at the rows of W."""
    e = np.exp(-np.sum(W * W, axis=1)[:, None] / TWIST_WIDTHS ** 2)
    alpha = (TWIST_AMPLITUDES * (1.0 - e)).sum(axis=1)
    beta = (TWIST_AMPLITUDES * (2.0 / TWIST_WIDTHS ** 2) * e).sum(axis=1)
    p, q = TWIST_PLANE
    c0, c1 = W @ p, W @ q
    n = W.shape[1]
    R = (np.eye(n)[None] + (np.cos(alpha) - 1.0)[:, None, None] * (np.outer(p, p) + np.outer(q, q))[None]
         + np.sin(alpha)[:, None, None] * (np.outer(q, p) - np.outer(p, q))[None])
    SW = c0[:, None] * q - c1[:, None] * p
    inner = np.eye(n)[None] + beta[:, None, None] * SW[:, :, None] * W[:, None, :]
    return np.einsum("kij,kj->ki", R, W), R @ inner @ JW
''')
    one_state = _one_state(model, mix, warp, twist, max_speed)
    core = ("    with np.errstate(over=\"ignore\", invalid=\"ignore\"):\n"
            "        F = np.einsum(\"kij,nj->nki\", COEFFICIENTS, monomials(Z))\n"
            "        V = np.einsum(\"tk,tki->ti\", responsibilities(Z), F) * SCALE\n") if warp is None else (
            "    U, J = warp(Z)\n"
            "    with np.errstate(over=\"ignore\", invalid=\"ignore\"):\n"
            "        F = np.einsum(\"kij,nj->nki\", COEFFICIENTS, monomials(U))\n"
            "        W = np.einsum(\"tk,tki->ti\", responsibilities(U), F)\n"
            "        V = np.linalg.solve(J, W[:, :, None])[:, :, 0] * SCALE\n")
    return _header(model, "#", max_speed) + f'''"""Standalone evaluator of a CDSP motion model: predict(X, goal=None) -> velocities."""
import math
from operator import mul

import numpy as np

UNITS = {ascii(str(model.units_))}
COLUMNS = {ascii(tuple(map(str, model.names())))}     # the names of the state's coordinates
GOAL = np.array({_literal(model.goal_)})
SCALE = {float(model.scale_)!r}
MAX_SPEED = {max_speed!r}     # None, or the largest |xdot| (units/s): the speed limit below
SPEED_KNEE = {SPEED_KNEE!r}    # velocities slower than SPEED_KNEE * MAX_SPEED are not changed
# None, or the speed floor (RATE 1/s, BOOST[, RADIUS]): xdot scaled by min(BOOST, max(1, RATE |x - goal| / |xdot|)),
# RATE faded to 0 from RADIUS / 2 to RADIUS (the settle zone; none given: everywhere)
FLOOR = {_floor_literal(model.floor_)}
# the mixture of h_k(z), in z coordinates: weights pi_k, means mu_k, covariances S_k
WEIGHTS = np.array({_literal(mix.weights)})
MEANS = np.array({_literal(mix.means)})
COVARIANCES = np.array({_literal(mix.covariances)})
{gating_py(mix)}EXPONENTS = np.array({_literal(model.field_exps_)}, dtype=np.int64)
COEFFICIENTS = np.array({_literal(model.C_)})     # (K, n, m): f_k,i(z) = sum_j C[k, i, j] z^e_j

DIM = GOAL.size
{MIXTURE_PY}{warp_defs}

def monomials(Z):
    """(N, m) values z^e_j at the rows of Z."""
    out = np.ones((Z.shape[0], EXPONENTS.shape[0]))
    for i in range(EXPONENTS.shape[1]):
        if EXPONENTS[:, i].any():
            out *= Z[:, i:i + 1] ** EXPONENTS[None, :, i]
    return out


{RESPONSIBILITIES_PY}

def predict(X, goal=None):
    """Velocities at the states X: shape (m, n) -> (m, n), or (n,) -> (n,); towards ``goal``
    (shape (n,); None: GOAL), the field translated to it."""
    if (type(X) is np.ndarray and X.shape == (DIM,) and X.dtype.kind == "f" and math.isfinite(X.sum())
            and (goal is None or (type(goal) is np.ndarray and goal.shape == (DIM,) and goal.dtype.kind == "f"
                                  and math.isfinite(goal.sum())))):
        v = one_state(X, GOAL if goal is None else goal)
        if v is not None:
            return v
    X = np.asarray(X, dtype=float)
    single = X.ndim == 1
    X = X[None, :] if single else X
    if X.ndim != 2 or X.shape[1] != DIM:
        raise ValueError(f"X must have shape (m, {{DIM}}) or ({{DIM}},), got {{np.shape(X)}}")
    if not np.isfinite(X).all():
        raise ValueError("X contains NaN or inf")
    goal = GOAL if goal is None else np.asarray(goal, dtype=float)
    if goal.shape != GOAL.shape or not np.isfinite(goal).all():
        raise ValueError(f"goal must be {{DIM}} finite numbers, got {{goal}}")
    Z = (X - goal) / SCALE
{core}    bad = np.flatnonzero(~np.isfinite(V).all(axis=1))
    if bad.size:
        raise ValueError(f"X row {{bad[0]}} is so far from the data (scale {{SCALE:.3g}}) that the field "
                         "overflows float. Try: states within a few orders of magnitude of the data.")
    if FLOOR is not None:
        V = floored(X - goal, V, *FLOOR)
    if MAX_SPEED is not None:
        V = limit_speed(V, MAX_SPEED)
    return V[0] if single else V


# The speed limit: sosdyn.lfd.runtime.states's own functions.
{SPEED_LIMIT_PY}

# The speed floor on arrays: sosdyn.lfd.fit.floor's own functions.
BOOST = {BOOST!r}
{FLOOR_PY}

# One state in plain floats: the predictor's own functions (sosdyn.lfd.runtime.predictor).
{one_state}'''


def _one_state(model, mix, warp, twist, max_speed) -> str:
    """The generated module's one-state path: :mod:`.predictor`'s functions (source embedded) on
    their tables (literals: ``repr`` of floats round-trips), ``one_state(x)`` -> xdot or None
    where the batch path must decide (a form overflows, or the velocity is not finite)."""
    n = model.dim_
    funcs = [gating, _monomial, field2 if n == 2 else fieldn, floor_factor]
    if warp is not None:
        funcs += [warp_forward2, warp_back2] if n == 2 else [warp_forward, warp_back]
    if twist is not None:
        funcs += [twist_forward, twist_back]
    fwd, back, field = ("warp_forward2", "warp_back2", "field2") if n == 2 else ("warp_forward", "warp_back", "fieldn")
    core = f"{field}(_TABLES, z, _far)" if twist is None else \
        f"twist_back(_TWIST, turn, {field}(_TABLES, z, _far))"
    body = (f"        v = {core}" if warp is None else
            f"        z, grads = {fwd}(_MAPS, z)\n" +
            ("" if twist is None else "        z, turn = twist_forward(_TWIST, z)\n") +
            f"        v = {back}(_MAPS, grads, {core})")
    return "\n\n".join(inspect.getsource(f) for f in funcs) + f"""

_TABLES = {tables(mix, model.C_, model.field_exps_)!r}
_MAPS = {None if warp is None else warp_tables(*warp)!r}
_TWIST = {None if twist is None else twist_tables(*twist)!r}


class _Far(Exception):
    pass


def _far(z):
    raise _Far


def one_state(x, goal):
    \"\"\"xdot at one finite state x (n,) for a finite goal (n,); None where the batch path decides.\"\"\"
    z = ((x - goal) / SCALE).tolist()
    try:
{body}
    except _Far:
        return None
    v = [SCALE * a for a in v]
    if not math.isfinite(sum(v)):
        return None
    if FLOOR is not None:
        f = floor_factor((x - goal).tolist(), v, *FLOOR)
        v = [f * a for a in v]
    if MAX_SPEED is not None:
        v = limit_speed_one(v, MAX_SPEED)
    return np.array(v)
"""

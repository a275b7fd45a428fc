"""Fast evaluation of a fitted CDSP field at one state, for control loops.

:meth:`sosdyn.lfd.model.cdsp.CDSP.predict` is vectorised over many states; for one state its
einsums, validation and error-state handling cost about 0.5 ms. :class:`StatePredictor`
computes the same numbers with everything that does not depend on x precomputed once:

    z = (x - x*) / s
    d = A z - b,     A = [L_1^-1; ...; L_K^-1]  (K n x n),   b_k = L_k^-1 mu_k     (S_k = L_k L_k^T)
    q_k = |d_k|^2,  tau = max(1, min_k q_k / c) (1 without a gating bound c; :mod:`sosdyn.lfd.fit.gmm`)
    l_k = c_k - 1/2 q_k / tau,    c_k = log pi_k - sum_i log L_k,ii - n/2 log 2 pi
    (with a fade F where tau > F: l_k <- log pi_k + (l_k - log pi_k) F / tau)
    h = exp(l - max l) / sum exp(l - max l)
    xdot = s * (h^T C) z^E,      C reshaped to (K, n m),  z^E the m monomial values of z

and with a warp (:mod:`.warp`; bumps c_j, v_j, sigma_j in z-units, rho_j(0) precomputed)

    g_j = -2/sigma_j^2 rho_j(u) (u - c_j),   u <- u + (rho_j(u) - rho_j(0)) v_j,      j = 1..m
    w = (h(u)^T C) u^E,   w <- w - v_j (g_j.w) / (1 + g_j.v_j),   j = m..1,      xdot = s w

since J_phi = A_m ... A_1, A_j = I + v_j g_j^T, and A_j^-1 = I - v_j g_j^T / (1 + g_j.v_j)
(Sherman-Morrison; 1 + g_j.v_j >= 1 - l_j > 0): O(m n) plain float arithmetic, no matrix
(:func:`warp_forward` / :func:`warp_back`; unrolled for n = 2, the common case, 3-4x faster).
With a twist about the goal after the bumps (:mod:`~sosdyn.lfd.fit.twist`: plane p, q, terms a_j,
tau_j), between the two passes

    alpha = sum_j a_j (1 - e_j),  beta = sum_j 2 a_j / tau_j^2 e_j,  e_j = exp(-|w|^2 / tau_j^2)
    u = R(alpha) w,     w' = (I - beta (S w) w^T) R(alpha)^T w'      (:func:`twist_forward`, :func:`twist_back`)

(R(alpha) the rotation by alpha in the plane, S w = (p.w) q - (q.w) p): J_T^-1 in closed form.
The mixture and field run in plain floats too (precomputed tuples, ``math.exp``; n = 2 unrolled):
for small n numpy's per-call cost (about 1 us a call) is most of the time. Bound with a warp:
about 0.4 us of Python per bump, forward and back. The forward pass cannot be fused into a few
numpy calls over all bumps: u_j+1 depends on u_j through rho_j, and the fixed-point (Jacobi)
iteration over all bumps at once took a median of 10 sweeps (3-14) of about 6 numpy calls each on
a LASA warp of 38 bumps to settle at 1e-15: slower than the loop.

which is the same sum as ``predict`` (the quadratic forms |L_k^-1 (z - mu_k)|^2 written as
|L_k^-1 z - L_k^-1 mu_k|^2), equal to it to rounding (about 1e-15 relative). Where a quadratic
form overflows (|z| ~ 1e154 and up) the predictor falls back on the mixture's own
:meth:`~sosdyn.lfd.fit.gmm.PositionMixture.responsibilities`, so the far-field behaviour is the
same as ``predict``'s too.

The single-state arithmetic is module functions on plain tuples (:func:`tables`, :func:`field2`,
:func:`fieldn`, :func:`warp_forward2`, ...): the Python export (:mod:`.export_python`) embeds their
source, so its one-state path is this code, not a copy.

Runtime goal: ``predictor(x, goal=g)`` evaluates the model with its goal moved to g, i.e. the
goal-shifted field translated, s f((x - g) / s) = predictor(x - g + x*): what a rollout uses
after a goal change. Speed limit (``max_speed``): the velocity scaled by the smooth positive factor
of :mod:`.states` (:func:`~.states.limit_speed_one`; unchanged below half the limit).

A predictor is a snapshot of the model's arrays: refit or reload the model, then build a new one.
"""
from __future__ import annotations

import math
from operator import mul

import numpy as np

from sosdyn.errors import InputError
from ..fit.floor import floor_terms
from ..fit.gmm import PositionMixture
from .states import as_state, check_max_speed, limit_speed_one


class StatePredictor:
    """xdot = f(x) at one state x of shape (n,), for a control loop; ``predictor(x, goal=None)``.

    Built from a fitted model's arrays (:meth:`sosdyn.lfd.model.cdsp.CDSP.predictor` does this):
    goal x* (n,), scale s, the position mixture, coefficients C (K, n, m), exponents E (m, n),
    the warp (centers, vectors, sigmas) in z-units or None, the speed limit or None, the twist
    after the warp's bumps (plane, amplitudes, widths; z-units) or None, and the speed floor
    ({"rate", "boost"}, and "radius" for a settle zone; :mod:`~sosdyn.lfd.fit.floor`) or None (applied
    before the speed limit).
    """

    def __init__(self, goal: np.ndarray, scale: float, mixture: PositionMixture, C: np.ndarray,
                 exps: np.ndarray, warp=None, max_speed: float | None = None, twist=None, floor=None):
        n = C.shape[1]
        self.dim, self._shape = n, (n,)
        self._goal = np.array(goal, dtype=float)
        self._scale = float(scale)
        self._tables = tables(mixture, C, exps)
        self._far = lambda z: mixture.responsibilities(np.array(z)[None])[0].tolist()
        self._maps = None if warp is None else warp_tables(*warp)
        self._twist = None if twist is None else twist_tables(*twist)
        self._forward, self._back = (warp_forward2, warp_back2) if n == 2 else (warp_forward, warp_back)
        self.max_speed = check_max_speed(max_speed)
        self._field = field2 if n == 2 else fieldn
        self._floor = None if floor is None else floor_terms(floor)

    def __call__(self, x, goal=None) -> np.ndarray:
        """xdot (n,) at the state x (n,), in the data's units, for the goal ``goal`` (None: the
        model's); the same numbers as ``model.predict(x[None] - goal + model.goal_)[0]``, then
        the speed limit. Raises InputError for text, complex numbers, a wrong shape, NaN/inf, or
        a state so far away that the field overflows float."""
        x = self._state(x, "x")
        goal = self._goal if goal is None else self._state(goal, "goal")
        z = ((x - goal) / self._scale).tolist()
        grads = None
        if self._maps is not None:                   # w = B(z) and the gradients g_j
            z, grads = self._forward(self._maps, z)
        if self._twist is not None:                  # u = T(w)
            z, turn = twist_forward(self._twist, z)
        v = self._field(self._tables, z, self._far)
        if self._twist is not None:                  # J_T^-1 v
            v = twist_back(self._twist, turn, v)
        if grads is not None:                        # J_B^-1 v
            v = self._back(self._maps, grads, v)
        s = self._scale
        v = [s * a for a in v]
        if not math.isfinite(sum(v)):
            raise InputError(f"x = {x} is so far from the data (scale {self._scale:.3g}) that the field "
                             "overflows float. Try: states within a few orders of magnitude of the "
                             "demonstrations.")
        if self._floor is not None:
            f = floor_factor((x - goal).tolist(), v, *self._floor)
            v = [f * a for a in v]
        if self.max_speed is not None:
            v = limit_speed_one(v, self.max_speed)
        return np.array(v)

    def _state(self, value, what: str) -> np.ndarray:
        """``value`` as a finite float (n,): a finite float array of shape (n,) as it is (the
        control-loop case, no copy), anything else through :func:`~.states.as_state`."""
        if (type(value) is np.ndarray and value.shape == self._shape and value.dtype.kind == "f"
                and math.isfinite(value.sum())):
            return value
        return as_state(value, self.dim, what)     # lists, tuples, integers, anything wrong


def tables(mixture: PositionMixture, C: np.ndarray, exps: np.ndarray) -> tuple:
    """The plain-float tables of :func:`field2` / :func:`fieldn`: (per component (L_k^-1 rows
    flattened, b_k, c_k), the gating (None, or its bound c, its fade F or None and log pi_k), C^T (n m, K),
    n, m, E rows, whether z^E = z)."""
    inv, lognorm = mixture.factors()
    K, n, m = C.shape
    b = np.einsum("kij,kj->ki", inv, mixture.means)
    mix = tuple((*map(float, inv[k].ravel()), *map(float, b[k]), float(lognorm[k])) for k in range(K))
    gate = None if mixture.bound is None else (float(mixture.bound), None if mixture.fade is None else
                                               float(mixture.fade), tuple(map(float, np.log(mixture.weights))))
    return (mix, gate,
            tuple(tuple(map(float, r)) for r in C.reshape(K, n * m).T), n, m,
            tuple(tuple(int(e) for e in r) for r in exps), bool(np.array_equal(exps, np.eye(n))))


def warp_tables(centers, vectors, sigmas) -> tuple:
    """The plain-float bumps of :func:`warp_forward` (n-tuples) / :func:`warp_forward2` (unrolled):
    (c_j, v_j, 1/sigma_j^2, rho_j(0))."""
    return tuple((tuple(map(float, c)), tuple(map(float, v)), 1.0 / float(s) ** 2,
                  math.exp(-float(np.dot(c, c)) / float(s) ** 2)) for c, v, s in zip(centers, vectors, sigmas))


def gating(mix: tuple, gate, lj: list, z: list, far) -> list:
    """h from l_k = c_k - q_k / 2 (module docstring): softmax(l), tempered where min q > bound for
    ``gate`` = (bound, fade, log pi) (q_k = 2 (c_k - l_k), tau = min q / bound, l_k <- c_k - (q_k / tau) / 2;
    with a fade where tau > fade, l_k <- log pi_k + (l_k - log pi_k) fade / tau); ``far(z)`` where an l_k
    is not finite (a quadratic form overflowed)."""
    if not math.isfinite(sum(lj)):
        return far(z)
    if gate is not None:
        bound, fade, logw = gate
        q = [2.0 * (r[-1] - a) for r, a in zip(mix, lj)]
        if min(q) > bound:                              # tempered off the data
            tau = min(q) / bound
            lj = [r[-1] - 0.5 * (a / tau) for r, a in zip(mix, q)]
            if fade is not None and tau > fade:         # and faded to pi farther off
                lj = [w + (a - w) / (tau / fade) for w, a in zip(logw, lj)]
    top = max(lj)
    e = [math.exp(a - top) for a in lj]
    t = sum(e)
    return [a / t for a in e]


def field2(T: tuple, z: list, far) -> list:
    """:func:`fieldn` for n = 2, unrolled."""
    mix, gate, Ct, _, m, et, linear = T
    z0, z1 = z
    lj = []
    for a00, a01, a10, a11, b0, b1, c in mix:
        d0, d1 = a00 * z0 + a01 * z1 - b0, a10 * z0 + a11 * z1 - b1
        lj.append(c - 0.5 * (d0 * d0 + d1 * d1))
    h = gating(mix, gate, lj, z, far)
    g = [sum(map(mul, col, h)) for col in Ct]               # h^T C, (2 m,)
    try:
        if linear:
            return [g[0] * z0 + g[1] * z1, g[2] * z0 + g[3] * z1]
        mono = [_monomial(z, e) for e in et]
        return [sum(map(mul, g[:m], mono)), sum(map(mul, g[m:], mono))]
    except OverflowError:
        return [math.inf, math.inf]


def fieldn(T: tuple, z: list, far) -> list:
    """(h(z)^T C) z^E in plain floats for the tables T (:func:`tables`; module docstring), h tempered
    by the gating; ``far(z)`` gives h where a quadratic form overflows."""
    mix, gate, Ct, n, m, et, linear = T
    lj = []
    for r in mix:
        d = [sum(map(mul, r[i * n:(i + 1) * n], z)) - r[n * n + i] for i in range(n)]
        lj.append(r[-1] - 0.5 * sum(map(mul, d, d)))
    h = gating(mix, gate, lj, z, far)
    g = [sum(map(mul, col, h)) for col in Ct]               # h^T C, (n m,)
    try:
        mono = z if linear else [_monomial(z, e) for e in et]
        return [sum(map(mul, g[i * m:(i + 1) * m], mono)) for i in range(n)]
    except OverflowError:
        return [math.inf] * n


def floor_factor(d: list, v: list, rate: float, boost: float, radius: float = math.inf) -> float:
    """sigma = min(boost, max(1, rate fade(|d| / radius) |d| / |v|)) for d = x - x* and v = f(x) (data
    units; the speed floor, :func:`~sosdyn.lfd.fit.floor.floored`, with its settle zone's fade written
    out): 1 at the goal, boost where v = 0 elsewhere in the zone."""
    dist, speed = math.hypot(*d), math.hypot(*v)              # hypot: no overflow where |v|^2 would
    s = min(1.0, max(0.0, 2.0 * (1.0 - dist / radius)))
    want = rate * s * s * (3.0 - 2.0 * s) * dist
    if speed > 0:
        return min(boost, max(1.0, want / speed))
    return boost if want > 0 else 1.0


def _monomial(z: list, e: tuple) -> float:
    """prod_i z_i^e_i."""
    p = 1.0
    for a, k in zip(z, e):
        p *= a ** k if k else 1.0
    return p


def warp_forward(maps, z: list) -> tuple[list, list]:
    """(u = phi(z), [g_j]) for ``maps`` [(c_j, v_j, 1/sigma_j^2, rho_j(0))] (module docstring)."""
    u, grads = z, []
    for c, v, w, rg in maps:
        d = [a - b for a, b in zip(u, c)]
        rho = math.exp(-w * sum(map(mul, d, d)))
        k, t = -2.0 * w * rho, rho - rg
        grads.append([k * a for a in d])
        u = [a + t * b for a, b in zip(u, v)]
    return u, grads


def warp_back(maps, grads: list, w: list) -> list:
    """J_phi^-1 w = A_1^-1 ... A_m^-1 w, A_j^-1 = I - v_j g_j^T / (1 + g_j.v_j)."""
    for (_, v, _, _), g in zip(reversed(maps), reversed(grads)):
        r = sum(map(mul, g, w)) / (1.0 + sum(map(mul, g, v)))
        w = [a - r * b for a, b in zip(w, v)]
    return w


def warp_forward2(maps, z: list) -> tuple[list, list]:
    """:func:`warp_forward` for n = 2, unrolled."""
    (u0, u1), grads = z, []
    for (c0, c1), (v0, v1), w, rg in maps:
        d0, d1 = u0 - c0, u1 - c1
        rho = math.exp(-w * (d0 * d0 + d1 * d1))
        k, t = -2.0 * w * rho, rho - rg
        grads.append((k * d0, k * d1))
        u0, u1 = u0 + t * v0, u1 + t * v1
    return [u0, u1], grads


def warp_back2(maps, grads: list, w: list) -> list:
    """:func:`warp_back` for n = 2, unrolled."""
    w0, w1 = w
    for (_, (v0, v1), _, _), (g0, g1) in zip(reversed(maps), reversed(grads)):
        r = (g0 * w0 + g1 * w1) / (1.0 + g0 * v0 + g1 * v1)
        w0, w1 = w0 - r * v0, w1 - r * v1
    return [w0, w1]


def twist_tables(plane, amplitudes, widths) -> tuple:
    """The plain-float twist of :func:`twist_forward`: (p, q, ((a_j, 1/tau_j^2), ...))."""
    return (tuple(map(float, plane[0])), tuple(map(float, plane[1])),
            tuple((float(a), 1.0 / float(t) ** 2) for a, t in zip(amplitudes, widths)))


def twist_forward(T: tuple, w: list) -> tuple[list, tuple]:
    """(u = T(w) = R(alpha) w, what :func:`twist_back` needs) for the twist T (:func:`twist_tables`):
    R(alpha) w = w + ((cos - 1) c0 - sin c1) p + ((cos - 1) c1 + sin c0) q, c0 = p.w, c1 = q.w."""
    p, q, terms = T
    r2 = sum(map(mul, w, w))
    alpha = beta = 0.0
    for a, k in terms:
        e = math.exp(-k * r2)
        alpha += a * (1.0 - e)
        beta += 2.0 * a * k * e
    cos, sin = math.cos(alpha), math.sin(alpha)
    c0, c1 = sum(map(mul, p, w)), sum(map(mul, q, w))
    a0, a1 = (cos - 1.0) * c0 - sin * c1, (cos - 1.0) * c1 + sin * c0
    return [x + a0 * y + a1 * z for x, y, z in zip(w, p, q)], (w, cos, sin, beta, c0, c1)


def twist_back(T: tuple, turn: tuple, v: list) -> list:
    """J_T(w)^-1 v = (I - beta (S w) w^T) R(alpha)^T v, S w = c0 q - c1 p (``turn`` from :func:`twist_forward`)."""
    p, q, _ = T
    w, cos, sin, beta, c0, c1 = turn
    d0, d1 = sum(map(mul, p, v)), sum(map(mul, q, v))
    a0, a1 = (cos - 1.0) * d0 + sin * d1, (cos - 1.0) * d1 - sin * d0
    y = [x + a0 * b + a1 * c for x, b, c in zip(v, p, q)]
    t = sum(beta * a * b for a, b in zip(w, y))          # beta w first: 0, not 0 * inf, far out
    return [x - t * (c0 * c - c1 * b) for x, b, c in zip(y, p, q)]

"""A diffeomorphic pre-warp: a composition of Gaussian bumps, invertible by construction.

The map (Perrin & Schlehuber-Caissier 2016, with a correction that fixes the goal g) is

    phi = psi_m o ... o psi_1,   psi_j(x) = x + (rho_j(x) - rho_j(g)) v_j,
    rho_j(x) = exp(-|x - c_j|^2 / sigma_j^2).

*Invertible.* |grad rho_j| <= sqrt(2) e^{-1/2} / sigma_j (attained at |x - c_j| = sigma_j/sqrt 2),
so psi_j = id + q_j with Lip(q_j) <= l_j = |v_j| sqrt(2) e^{-1/2} / sigma_j. When l_j < 1,
psi_j is a bijection of R^n (x = u - q_j(x) is a contraction in x for every u; Banach), smooth,
with J_psi_j = I + v_j grad rho_j^T, whose singular values lie in [1 - l_j, 1 + l_j]. Hence phi is
a global diffeomorphism with

    prod_j (1 - l_j) <= sigma_min(J_phi(x)) <= sigma_max(J_phi(x)) <= prod_j (1 + l_j)   for all x.

*Goal.* psi_j(g) = g for every j (the constant rho_j(g) v_j is subtracted; it changes no Jacobian
and no Lipschitz number), so phi(g) = g.

*Inverse.* psi_j(x) = u means x = u - t v_j with the scalar t solving t = rho_j(u - t v_j) - rho_j(g),
one increasing equation in t (slope in [1 - l_j, 1 + l_j]); :func:`invert` solves it map by map, last
map first (bracketed Newton).

*Fit.* :func:`fit_maps` moves points X (N, n) onto targets Y (N, n) greedily: at step j, among the
8 points of largest mismatch |Y_i - phi_{j-1}(X_i)|, the centre c_j = phi_{j-1}(X_i), the vector
v_j = beta (Y_i - phi_{j-1}(X_i)) shrunk so that l_j <= l_max, and sigma_j from a geometric grid,
the combination that most lowers the sum of squared mismatches (the fit stops when none lowers it).
:func:`radial_targets` gives the targets CDSP's warp uses by default (:func:`fit_warp`): each
point moved along its ray from g to (1 - decay s_i) times the running minimum of |x - g| (s_i the
arc-length fraction), a path along which |u - g| never increases (strictly decreases for decay > 0),
the property a contracting system with a constant metric imposes; :func:`isotonic_targets` the
nearest such path in log-distance (the start may move out as the far part moves in: a smaller
deformation where a path starts near g and swings far out, :func:`decreasing_fit`);
:func:`line_targets` the segment from the curve's start to g (a larger deformation).
"""
from __future__ import annotations

import math

import numpy as np

from sosdyn.errors import InputError
from ..data.demonstrations import resample_in_time

#: A warp's settings (CDSP's ``warp`` dict; every key optional): at most n_maps bumps, each l_j <= l_max,
#: each removing the fraction beta of the mismatch; n_points samples per time-normalised curve; match
#: "mean" (the mean training demonstration) or "each" (every one); target "radial" (decay in [0, 1]) or
#: "line" or "isotonic"; twist: the shear bound K of a twist about the goal composed after the bumps
#: (0: none; :mod:`.composite`, :mod:`.twist`). The defaults: the single setting of lowest 26-shape TRAINING
#: DTWD on LASA (docs/findings.md).
WARP_DEFAULTS = {"n_maps": 100, "l_max": 0.5, "beta": 0.5, "n_points": 100, "match": "mean", "target": "radial",
                 "decay": 0.75, "twist": 0.0}
#: The warped candidates of ``warp="auto"`` (with the plain fit): the pair of lowest 26-shape TRAINING
#: mean when chosen per shape with the plain fit (problems/lasa_warp.py), and the isotonic target (issue 36:
#: it follows the winding set's swings; on LASA, random_state 0, it changes the kept fit of 2 (standard split)
#: and 6 (swapped) of the 26 shapes, the test means 796.08 -> 796.07 and 1114.1 -> 1102.2, docs/theory.md).
AUTO_WARPS = {"60 maps, decay 0.75": dict(WARP_DEFAULTS, n_maps=60),
              "60 maps, decay 1": dict(WARP_DEFAULTS, n_maps=60, decay=1.0),
              "60 maps, isotonic": dict(WARP_DEFAULTS, n_maps=60, decay=1.0, target="isotonic")}
#: Fitted as well, and chosen from with the others by the same rule, only when the best of those deviates
#: from its training demonstrations by more than ESCALATE x the training box's diagonal: the isotonic
#: target matched to every demonstration (it reaches paths that start near the goal and swing far out,
#: where the mean's warp fails; as a plain candidate it fits LASA's training demos closer and its test
#: demos worse, docs/theory.md).
ESCALATE, ESCALATE_WARPS = 0.05, {"60 maps, isotonic, each": dict(AUTO_WARPS["60 maps, isotonic"], match="each")}
MATCHES, TARGETS = ("mean", "each"), ("radial", "isotonic", "line")
CHECK_BOX = 2.0                 # the singular-value check samples |z|_inf <= CHECK_BOX (the certificate's box)
BOUND_TOL = 1e-9                # relative slack of the sampled singular-value bound
LIP_FACTOR = math.sqrt(2.0) * math.exp(-0.5)     # sup |grad exp(-|x|^2/s^2)| * s
SIGMA_GRID = np.geomspace(0.03, 1.0, 12)        # sigma / data scale tried at each fitting step
MAX_MAPS = 10_000               # bumps of one warp, fitted or loaded (a load checks J_phi at 10^4 states: 1.4-1.9 s)
#: The floor of prod_j (1 - l_j), the certified lower bound on sigma_min(J_phi): below it J_phi may be
#: so near singular that J_phi^-1 multiplies velocities by up to 1 / floor. Fitted warps stay far above
#: it: the 30 LASA shapes under the three warp settings of "auto" reach 7.0e-8 at the lowest.
MIN_CONDITION = 1e-12
UNDERFLOW = 800.0               # exp(-q) is exactly 0.0 in float for q > 745.2: no J update there
FIT_CHUNK = 2_000_000           # numbers of trial bumps' images (centres x sigmas x points) held at once


def lipschitz_numbers(vectors: np.ndarray, sigmas: np.ndarray) -> np.ndarray:
    """l_j = |v_j| sqrt(2) e^{-1/2} / sigma_j, the Lipschitz number of psi_j - id (m,)."""
    return np.linalg.norm(np.asarray(vectors, float), axis=1) * LIP_FACTOR / np.asarray(sigmas, float)


def check_maps(centers, vectors, sigmas, goal, *, what: str = "warp") -> tuple[np.ndarray, ...]:
    """The map's arrays as floats, checked: shapes (m, n), (m, n), (m,), (n,), finite, sigma_j > 0 and
    every l_j < 1 (psi_j a diffeomorphism). InputError naming the first violation."""
    C, V, S, g = (np.asarray(a, dtype=float) for a in (centers, vectors, sigmas, goal))
    m = S.shape[0] if S.ndim == 1 else -1
    if g.ndim != 1 or C.shape != (m, g.size) or V.shape != (m, g.size):
        raise InputError(f"{what}: centers {C.shape}, vectors {V.shape}, sigmas {S.shape} and goal {g.shape} "
                         "must have shapes (m, n), (m, n), (m,) and (n,). Try: arrays from fit_maps.")
    if not all(np.isfinite(a).all() for a in (C, V, S, g)) or not (S > 0).all():
        raise InputError(f"{what}: every number must be finite and every sigma > 0. Try: arrays from fit_maps.")
    if m > MAX_MAPS:
        raise InputError(f"{what}: {m} maps, more than {MAX_MAPS} (what a fit makes at most). "
                         f"Try: a warp of at most {MAX_MAPS} maps (CDSP(warp={{'n_maps': ...}})).")
    lip = lipschitz_numbers(V, S)
    if m and lip.max() >= 1:
        j = int(lip.argmax())
        raise InputError(f"{what}: map {j} has Lipschitz number {lip[j]:.6g} >= 1 (|v| = "
                         f"{np.linalg.norm(V[j]):.6g}, sigma = {S[j]:.6g}): it may not be invertible. "
                         "Try: a smaller |v| or a larger sigma (l_max < 1 in fit_maps).")
    if m and np.sum(np.log1p(-lip)) < math.log(MIN_CONDITION):
        raise InputError(f"{what}: prod_j (1 - l_j) = {np.exp(np.sum(np.log1p(-lip))):.3g} is below "
                         f"{MIN_CONDITION:g}, so J_phi may be near singular (velocities multiplied by up "
                         f"to 1 / that); the largest l_j is {lip.max():.17g} (map {int(lip.argmax())}). "
                         "Try: fewer maps or a smaller l_max (fit_maps stops before this floor).")
    return C, V, S, g


def _bump(X: np.ndarray, c: np.ndarray, sigma: float) -> np.ndarray:
    """rho(x) = exp(-|x - c|^2 / sigma^2) at the rows of X."""
    return np.exp(-np.sum((X - c) ** 2, axis=-1) / sigma ** 2)


def bumps_at(x: np.ndarray, centers: np.ndarray, sigmas: np.ndarray) -> np.ndarray:
    """rho_j(x) for every map j at one point x (n,): (m,)."""
    return np.exp(-np.sum((x - np.asarray(centers)) ** 2, axis=1) / np.asarray(sigmas) ** 2)


def apply(X, centers, vectors, sigmas, goal) -> np.ndarray:
    """phi(X) at the rows of X (k, n)."""
    U = np.array(X, dtype=float)
    for c, v, s in zip(centers, vectors, sigmas):
        U += (_bump(U, c, s) - _bump(goal, c, s))[:, None] * v
    return U


def jacobian(X, centers, vectors, sigmas, goal) -> tuple[np.ndarray, np.ndarray]:
    """(phi(X), J_phi(X)): (k, n) and (k, n, n), by the chain rule J <- (I + v grad rho^T) J.

    Work proportional to what changes: J is updated only at the rows where rho_j is not exactly
    0 in float (|u - c_j|^2 / sigma_j^2 < UNDERFLOW; elsewhere grad rho_j = 0 and the update adds
    exactly 0), so tiny bumps cost O(k n) each, not O(k n^2); J is kept state-last, (n, n, k),
    for contiguous array operations. The numbers are those of the plain loop, bit for bit."""
    U = np.array(X, dtype=float)
    k, n = U.shape
    C, V, S = (np.asarray(a, dtype=float) for a in (centers, vectors, sigmas))
    rho_goal = np.exp(-np.sum((np.asarray(goal, dtype=float) - C) ** 2, axis=-1) / S ** 2)
    J = np.broadcast_to(np.eye(n)[:, :, None], (n, n, k)).copy()             # J[i, j, row]
    Ut = np.ascontiguousarray(U.T)                                          # (n, k)
    for c, v, s, rg in zip(C, V, S, rho_goal):
        D = Ut - c[:, None]
        q = np.sum(D ** 2, axis=0) / s ** 2
        rows = np.flatnonzero(q < UNDERFLOW)
        if rows.size == k:
            rho = np.exp(-q)
            J += v[:, None, None] * np.einsum("ik,ijk->jk", (-2.0 / s ** 2) * rho * D, J)[None]
            Ut += (rho - rg) * v[:, None]
        else:
            rho = np.exp(-q[rows])
            Jr = J[:, :, rows]
            J[:, :, rows] = Jr + v[:, None, None] * np.einsum("ik,ijk->jk", (-2.0 / s ** 2) * rho * D[:, rows], Jr)[None]
            step = np.full(k, -rg)                                           # rho - rho(goal), rho = 0 off the rows
            step[rows] = rho - rg
            Ut += step * v[:, None]
    return np.ascontiguousarray(Ut.T), np.ascontiguousarray(J.transpose(2, 0, 1))   # (k, n), (k, n, n) C order


def invert(U, centers, vectors, sigmas, goal, tol: float = 1e-14, max_iter: int = 200) -> np.ndarray:
    """phi^{-1}(U) at the rows of U (k, n): per map, last first, the root t of the increasing function
    h(t) = t - rho_j(u - t v_j) + rho_j(g) (h' in [1 - l_j, 1 + l_j]; h(-rho_j(g)) <= 0 <= h(1 - rho_j(g)))
    by Newton steps kept inside the bracket (bisection otherwise), to |h| <= tol."""
    X = np.array(U, dtype=float)
    for c, v, s in zip(centers[::-1], vectors[::-1], sigmas[::-1]):
        rg = _bump(goal, c, s)
        lo, hi = np.full(len(X), -rg), np.full(len(X), 1.0 - rg)
        t = np.zeros(len(X))
        for _ in range(max_iter):
            x = X - t[:, None] * v
            rho = _bump(x, c, s)
            h = t - rho + rg
            if np.abs(h).max(initial=0.0) <= tol:
                break
            lo, hi = np.where(h < 0, t, lo), np.where(h > 0, t, hi)
            step = t - h / (1.0 + (-2.0 / s ** 2) * rho * ((x - c) @ v))
            t = np.where((step > lo) & (step < hi), step, 0.5 * (lo + hi))
        X = X - t[:, None] * v
    return X


def line_targets(curve: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """The points of ``curve`` (N, n) moved onto the segment from curve[0] to ``goal``, point i at the
    curve's arc-length fraction s_i: goal + (1 - s_i)(curve[0] - goal)."""
    return goal + (1.0 - arc_fraction(curve))[:, None] * (curve[0] - goal)


def arc_fraction(curve: np.ndarray) -> np.ndarray:
    """s_i = arc length from curve[0] to curve[i] over the whole length (0 for a curve of length 0)."""
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(curve, axis=0), axis=1))])
    return arc / arc[-1] if arc[-1] > 0 else np.zeros_like(arc)


def radial_targets(curve: np.ndarray, goal: np.ndarray, decay: float = 0.0) -> np.ndarray:
    """The points of ``curve`` (N, n) moved along their rays from ``goal`` to the distance
    (1 - decay s_i) min_{k <= i} r_k (r_k = |curve_k - goal|, s_i the arc-length fraction): with
    decay = 0 the nearest curve along which |u - g| never increases; with decay in (0, 1] it
    strictly decreases."""
    d = curve - goal
    r = np.linalg.norm(d, axis=1)
    r_min = np.minimum.accumulate(r) * (1.0 - decay * arc_fraction(curve))
    return goal + d * np.divide(r_min, r, out=np.ones_like(r), where=r > 0)[:, None]


def decreasing_fit(y: np.ndarray) -> np.ndarray:
    """The non-increasing sequence nearest to ``y`` (N,) in least squares: pool adjacent violators
    (each violating pair of blocks merged into their mean, until none violates)."""
    means, sizes = [], []
    for v in np.asarray(y, dtype=float):
        means.append(float(v))
        sizes.append(1)
        while len(means) > 1 and means[-2] < means[-1]:
            m, k = means.pop(), sizes.pop()
            means[-1], sizes[-1] = (means[-1] * sizes[-1] + m * k) / (sizes[-1] + k), sizes[-1] + k
    return np.repeat(means, sizes)


def isotonic_targets(curve: np.ndarray, goal: np.ndarray, decay: float = 0.0) -> np.ndarray:
    """The points of ``curve`` (N, n) moved along their rays from ``goal`` to the distance
    (1 - decay s_i) rho_i, rho the non-increasing fit of log r_i (:func:`decreasing_fit`; r_i =
    |curve_i - goal|, points at the goal kept there, s_i the arc-length fraction): a path along which
    |u - g| never increases (strictly decreases for decay > 0), nearest to the curve in log-distance."""
    d = curve - goal
    r = np.linalg.norm(d, axis=1)
    out = r > 0
    rho = np.zeros_like(r)
    rho[out] = np.exp(decreasing_fit(np.log(r[out])))
    rho = np.minimum.accumulate(np.where(out, rho, 0.0)) * (1.0 - decay * arc_fraction(curve))
    return goal + d * np.divide(rho, r, out=np.ones_like(r), where=out)[:, None]


TARGET_FUNCTIONS = {"radial": radial_targets, "isotonic": isotonic_targets}


def _bump_errors(cur, miss, Y, goal, centres, grid, l_max: float, beta: float):
    """For every centre cur[i], i in ``centres``, and sigma in ``grid`` (row-major): the bump of
    vector beta miss_i shrunk to l <= l_max, and sum |Y - psi(cur)|^2. Returns (least error, its
    flat index, (psi(cur), vector) there)."""
    v = beta * miss[centres]                                                     # (c, n)
    norms = np.array([max(np.linalg.norm(r), 1e-300) for r in v])
    v = v[:, None, :] * np.minimum(1.0, l_max * grid[None, :] / (LIP_FACTOR * norms[:, None]))[:, :, None]
    d2 = np.sum((cur[None, :, :] - cur[centres][:, None, :]) ** 2, axis=-1)      # (c, N)
    rho = np.exp(-d2[:, None, :] / grid[None, :, None] ** 2)                     # (c, s, N)
    rho_goal = np.exp(-np.sum((goal - cur[centres]) ** 2, axis=-1)[:, None] / grid[None, :] ** 2)
    new = cur + (rho - rho_goal[:, :, None])[..., None] * v[:, :, None, :]       # (c, s, N, n)
    e = np.sum(((Y - new) ** 2).reshape(len(centres) * len(grid), -1), axis=1)
    k = int(np.argmin(e))
    return float(e[k]), k, (new.reshape((-1,) + cur.shape)[k], v.reshape(-1, cur.shape[1])[k])


def fit_maps(X: np.ndarray, Y: np.ndarray, goal: np.ndarray, n_maps: int, l_max: float, beta: float,
             scale: float, n_candidates: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Greedy matching of X onto Y (module docstring): (centers (m, n), vectors (m, n), sigmas (m,)),
    m <= n_maps, every l_j <= l_max, prod_j (1 - l_j) >= MIN_CONDITION (the fit stops before a map
    would take it lower); sigmas from ``scale`` * SIGMA_GRID; centres among the
    ``n_candidates`` points of largest mismatch (the one whose best bump lowers the mismatch most)."""
    cur, goal = np.array(X, dtype=float), np.asarray(goal, dtype=float)
    grid = scale * SIGMA_GRID
    centers, vectors, sigmas = [], [], []
    err = float(np.sum((Y - cur) ** 2))
    log_cond, floor = 0.0, math.log(MIN_CONDITION) - math.log1p(-l_max) + 1e-9   # log prod (1 - l_j); floor
    for _ in range(min(n_maps, MAX_MAPS)):
        if log_cond < floor:            # one more map might take prod (1 - l_j) below MIN_CONDITION
            break
        miss = Y - cur
        best = None
        top = np.argsort(-np.sum(miss ** 2, axis=1))[:n_candidates]
        for chunk in np.array_split(top, min(len(top), -(-len(top) * len(grid) * cur.size // FIT_CHUNK))):
            e, k, new = _bump_errors(cur, miss, Y, goal, chunk, grid, l_max, beta)
            if best is None or e < best[0]:         # the first (centre, sigma) of least error
                best = (e, cur[chunk[k // len(grid)]].copy(), grid[k % len(grid)], new[1], new[0])
        if best[0] >= err * (1 - 1e-6):
            break
        err, c, s, v, cur = best
        log_cond += math.log1p(-float(lipschitz_numbers(v[None], np.array([s]))[0]))
        centers.append(c)
        vectors.append(v)
        sigmas.append(s)
    n = X.shape[1]
    return (np.array(centers).reshape(-1, n), np.array(vectors).reshape(-1, n), np.array(sigmas, dtype=float))


def fit_warp(curves: list[tuple[np.ndarray, np.ndarray]], goal: np.ndarray, settings: dict
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A warp fixing ``goal`` fitted to the demonstrations ``curves`` [(t, pos)]: each resampled to
    n_points instants (their mean if match is "mean"), matched (:func:`fit_maps`, sigmas relative to
    the largest |pos - goal|) to its :func:`radial_targets`, :func:`isotonic_targets` or :func:`line_targets`. (centers, vectors,
    sigmas) in the curves' units; ``settings`` complete (WARP_DEFAULTS' keys, checked)."""
    goal = np.asarray(goal, dtype=float)
    scale = max(float(np.abs(pos - goal).max()) for _, pos in curves) or 1.0
    res = [resample_in_time(t, pos, settings["n_points"]) for t, pos in curves]
    res = [np.mean(res, axis=0)] if settings["match"] == "mean" else res
    X = np.vstack(res)
    Y = np.vstack([line_targets(c, goal) if settings["target"] == "line" else
                   TARGET_FUNCTIONS[settings["target"]](c, goal, float(settings["decay"])) for c in res])
    return fit_maps(X, Y, goal, int(settings["n_maps"]), float(settings["l_max"]), float(settings["beta"]), scale)


def pulled_back(Z: np.ndarray, maps, field) -> np.ndarray:
    """zdot = J_phi(z)^{-1} f(phi(z)) at the rows of Z (k, n), ``maps`` = (centers, vectors, sigmas)
    fixing 0, ``field`` f on rows of U. Since J_phi = A_m ... A_1, A_j = I + v_j g_j^T with the gradient
    g_j = -2/sigma_j^2 rho_j (u_j - c_j) at the j-th intermediate point u_j, and A_j^{-1} = I - v_j g_j^T /
    (1 + g_j.v_j) (Sherman-Morrison; 1 + g_j.v_j >= 1 - l_j > 0): forward u_{j+1} = u_j + (rho_j(u_j) -
    rho_j(0)) v_j, kept as u_j = w_j - s_j with w_{j+1} = w_j + rho_j v_j and the constant s_j = sum_{i<j}
    rho_i(0) v_i folded into the centres; back, from y = f(phi(z)), y <- y - v_j (g_j.y) / (1 + g_j.v_j) for
    j = m..1 (one pass of O(m n) per row, no n x n solve). The maps' arrays may also be per row, (m, k, n),
    (m, k, n), (m, k): each row its own warp (:func:`stacked_maps`). :func:`pull_back` prepares it for
    many calls with k rows."""
    return pull_back(maps, np.shape(Z)[0])(Z, field)


def pull_back(maps, k: int):
    """``pull(Z, field)``: :func:`pulled_back` (the same operations, the same numbers) for Z of k rows,
    everything that does not depend on Z computed once and every step's array made once (a rollout
    calls it once per Euler step: its cost is numpy's per-call overhead, about 9 calls per map)."""
    C, V, S = (np.asarray(a, dtype=float) for a in maps)
    m, n = len(S), np.shape(C)[-1]
    V = np.ascontiguousarray(np.broadcast_to(V[:, None, :] if V.ndim == 2 else V, (m, k, n)))
    C = np.broadcast_to(C[:, None, :] if C.ndim == 2 else C, (m, k, n))
    S2 = np.broadcast_to(S[:, None] ** 2 if S.ndim == 1 else S ** 2, (m, k))
    shift = np.cumsum(np.exp(-np.sum(C ** 2, axis=-1) / S2)[..., None] * V, axis=0)   # s_{j+1}
    centres = C + np.concatenate([np.zeros((1, k, n)), shift[:-1]])                     # c_j + s_j
    nS2, g2 = -S2[..., None], -2.0 / S2[..., None]
    D, R, G, Vd = np.empty((m, k, n)), np.empty((m, k, 1)), np.empty((m, k, n)), np.empty((m, k, n))
    q, tmp, gv = np.empty(k), np.empty((k, n)), np.empty((m, k))
    per_map = list(zip(D, R, centres, nS2, V))
    back = list(zip(G, Vd))[::-1]
    q1 = q[:, None]

    def pull(Z, field):
        W = np.array(Z, dtype=float)
        for Dj, Rj, cj, nS2j, Vj in per_map:
            np.subtract(W, cj, out=Dj)                                                   # u_j - c_j
            np.vecdot(Dj, Dj, out=q)
            np.exp(np.divide(q1, nS2j, out=Rj), out=Rj)                                  # rho_j(u_j)
            W += np.multiply(Rj, Vj, out=tmp)
        F = np.array(field(W - shift[-1] if m else W), dtype=float)
        np.multiply(np.multiply(g2, R, out=G), D, out=G)                                 # g_j
        np.divide(V, np.add(1.0, np.vecdot(G, V, out=gv), out=gv)[..., None], out=Vd)   # v_j / (1 + g_j.v_j)
        for Gj, Vdj in back:
            F -= np.multiply(np.vecdot(Gj, F, out=q)[:, None], Vdj, out=tmp)
        return F
    return pull


def stacked_maps(maps: list, rows: int, n: int):
    """Per-row maps for :func:`pulled_back`: block b of ``rows`` consecutive rows gets ``maps[b]``
    ((centers, vectors, sigmas) or None), every block padded to the most bumps with v = 0, c = 0,
    sigma = 1 (an identity map: its terms add exactly 0). None if no block has a bump."""
    m = max((len(mp[2]) for mp in maps if mp is not None), default=0)
    if m == 0:
        return None
    C, V, S = np.zeros((m, len(maps), n)), np.zeros((m, len(maps), n)), np.ones((m, len(maps)))
    for b, mp in enumerate(maps):
        if mp is not None:
            k = len(mp[2])
            C[:k, b], V[:k, b], S[:k, b] = mp
    return tuple(np.repeat(a, rows, axis=1) for a in (C, V, S))


__all__ = ["AUTO_WARPS", "BOUND_TOL", "ESCALATE", "ESCALATE_WARPS", "CHECK_BOX", "LIP_FACTOR", "MATCHES", "MAX_MAPS", "MIN_CONDITION", "SIGMA_GRID",
           "TARGETS", "WARP_DEFAULTS",
           "apply", "arc_fraction", "bumps_at", "check_maps", "decreasing_fit", "fit_maps", "fit_warp", "invert",
           "isotonic_targets",
           "jacobian", "line_targets", "lipschitz_numbers", "pull_back", "pulled_back", "radial_targets", "stacked_maps"]

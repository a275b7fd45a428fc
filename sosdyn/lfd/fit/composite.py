"""The warp CDSP fits through: u = phi(z) = T(B(z)), the bumps B (:mod:`.warp`), then the twist T
about the goal (:mod:`.twist`) when the settings ask for one.

A fitted model keeps it as ``warp_`` (None: no warp), a dict in z-units: the bumps' "centers"
(m, n), "vectors" (m, n) and "sigmas" (m,) (m may be 0 when there is a twist) and, with a twist,
"twist" = {"plane" (2, n), "amplitudes" (k,), "widths" (k,)}. Both maps fix the goal z = 0 and
are diffeomorphisms of R^n with

    prod_j (1 - l_j) / lam(K) <= sigma_min(J_phi(z)),    sigma_max(J_phi(z)) <= prod_j (1 + l_j) lam(K)

(the bumps' Lipschitz numbers l_j, the twist's shear bound K, lam(K) = (K + sqrt(K^2 + 4)) / 2;
lam = 1 without a twist): J_phi = J_T(B(z)) J_B(z), and singular values of a product lie
between the products of the factors' extremes. :func:`check` recomputes both bounds from the
stored numbers and compares them with J_phi, J_T at sampled states.

*Fit* (:func:`fit_composite`, data units): the bumps as :func:`~.warp.fit_warp`; the twist
(settings' ``twist`` = K > 0) on every demonstration resampled to ``n_points`` instants and moved
by the bumps (:func:`~.twist.fit_twist`, TWIST_TERMS widths, ridge TWIST_RIDGE, shear bound K).
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import InputError
from ..data.demonstrations import resample_in_time
from . import twist as tw
from .warp import CHECK_BOX, BOUND_TOL, apply as bump_apply, check_maps, fit_warp, jacobian as bump_jacobian, \
    lipschitz_numbers, pull_back, pulled_back as bump_pulled_back, stacked_maps

TWIST_TERMS = 12                # widths of a fitted twist (tau_j, twist.TAU_RANGE)
TWIST_RIDGE = 1e-6              # the least ridge on its amplitudes (a larger one meets the shear bound)
TWIST_KEYS = ("plane", "amplitudes", "widths")


def fit_composite(curves: list[tuple[np.ndarray, np.ndarray]], goal: np.ndarray, settings: dict):
    """(bumps (centers, vectors, sigmas), twist (plane, amplitudes, widths) or None) in the data's
    units, fitted to the demonstrations ``curves`` [(t, pos)] with ``settings`` (complete)."""
    goal = np.asarray(goal, dtype=float)
    maps = fit_warp(curves, goal, settings)
    if not settings["twist"]:
        return maps, None
    moved = [bump_apply(resample_in_time(t, pos, settings["n_points"]), *maps, goal) - goal for t, pos in curves]
    return maps, tw.fit_twist(moved, TWIST_TERMS, TWIST_RIDGE, float(settings["twist"]))


def z_units(fitted, goal, scale) -> dict | None:
    """The warp ``fitted`` (:func:`fit_composite`'s pair, data units) as a z-unit dict; None
    without bumps or twist."""
    if fitted is None:
        return None
    (C, V, S), twist = fitted
    if not len(S) and twist is None:
        return None
    out = {"centers": (C - goal) / scale, "vectors": V / scale, "sigmas": S / scale}
    if twist is not None:
        out["twist"] = {"plane": twist[0], "amplitudes": twist[1], "widths": twist[2] / scale}
    return out


def maps_of(warp: dict):
    """(centers, vectors, sigmas) of a z-unit warp dict."""
    return warp["centers"], warp["vectors"], warp["sigmas"]


def twist_of(warp: dict | None):
    """(plane, amplitudes, widths) of a z-unit warp dict's twist, or None."""
    t = None if warp is None else warp.get("twist")
    return None if t is None else (t["plane"], t["amplitudes"], t["widths"])


def apply(Z, warp: dict) -> np.ndarray:
    """phi(Z) = T(B(Z)) at the rows of Z (k, n)."""
    U = bump_apply(Z, *maps_of(warp), np.zeros(np.shape(Z)[1]))
    return U if twist_of(warp) is None else tw.apply(U, *twist_of(warp))


def jacobian(Z, warp: dict) -> tuple[np.ndarray, np.ndarray]:
    """(phi(Z), J_phi(Z)) at the rows of Z (k, n): J_T(B(z)) J_B(z)."""
    U, J = bump_jacobian(Z, *maps_of(warp), np.zeros(np.shape(Z)[1]))
    if twist_of(warp) is None:
        return U, J
    U, JT = tw.jacobian(U, *twist_of(warp))
    return U, JT @ J


def pulled_back(Z, warp: dict, field) -> np.ndarray:
    """J_phi(z)^{-1} field(phi(z)) at the rows of Z = J_B^{-1} J_T^{-1} field(T(B(z)))."""
    twist = twist_of(warp)
    inner = field if twist is None else (lambda W: tw.pulled_back(W, *twist, field))
    return bump_pulled_back(Z, maps_of(warp), inner)


def block_pull(warps: list, rows: int, n: int):
    """``pull(Z, field)``: :func:`pulled_back` of ``warps[b]`` (a z-unit dict or None) on the b-th
    of len(warps) blocks of ``rows`` consecutive rows of Z, all blocks in one pass (bumps per row,
    :func:`~.warp.stacked_maps` and :func:`~.warp.pull_back`; twists per row, a block without one
    given the identity twist, amplitudes 0); None when no block has a warp."""
    maps = stacked_maps([None if w is None else maps_of(w) for w in warps], rows, n)
    twists = [twist_of(w) for w in warps]
    if maps is None and all(t is None for t in twists):
        return None
    bumps = None if maps is None else pull_back(maps, rows * len(warps))
    if all(t is None for t in twists):
        return bumps
    m = max(len(t[1]) for t in twists if t is not None)
    plane, amps, widths = np.zeros((len(warps), 2, n)), np.zeros((len(warps), m)), np.ones((len(warps), m))
    for b, t in enumerate(twists):
        plane[b] = np.eye(2, n) if t is None else t[0]
        if t is not None:
            amps[b, :len(t[1])], widths[b, :len(t[2])] = t[1], t[2]
    plane, amps, widths = (np.repeat(a, rows, axis=0) for a in (plane, amps, widths))

    def pull(Z, field):
        inner = lambda W: tw.pulled_back(W, plane, amps, widths, field)      # noqa: E731
        return inner(Z) if bumps is None else bumps(Z, inner)
    return pull


def check(warp: dict, n_samples: int, seed: int) -> dict:
    """The warp's check (``CertificateReport.warp``): every l_j < 1 and the twist's arrays
    (:func:`~.twist.check_twist`) recomputed from the stored numbers, and at ``n_samples`` states
    uniform in |z|_inf <= CHECK_BOX drawn with ``seed``: sigma_min(J_phi) >= prod_j (1 - l_j) / lam(K),
    and with a twist 1/lam(K) <= sigma(J_T(B(z))) <= lam(K). The numbers and ``passed``; stored
    numbers that fail the array checks give max_lipschitz inf or twist_shear inf, and ``passed`` False."""
    C, V, S = maps_of(warp)
    n = np.shape(C)[1]
    try:
        check_maps(C, V, S, np.zeros(n))
        lip = lipschitz_numbers(V, S)
    except InputError:
        lip = np.array([np.inf])
    twist, shear, low = twist_of(warp), 0.0, 1.0
    if twist is not None:
        try:
            tw.check_twist(*twist)
            shear, low = tw.shear_bound(twist[1]), tw.singular_bound(twist[1])
        except InputError:
            shear, low = np.inf, 0.0
    bound = float(np.prod(1.0 - lip)) * low if lip.size else low
    ok = bool(np.isfinite(lip).all() and np.isfinite(shear))
    Z = np.random.default_rng(seed).uniform(-CHECK_BOX, CHECK_BOX, (n_samples, n))
    out = {"n_maps": len(S), "max_lipschitz": float(lip.max(initial=0.0)), "singular_bound": bound, "min_singular": 0.0}
    passed = ok and lip.max(initial=0.0) < 1 and bound > 0
    if ok:
        W, J = bump_jacobian(Z, C, V, S, np.zeros(n))
        if twist is not None:
            JT = tw.jacobian(W, *twist)[1]
            sv = np.linalg.svd(JT, compute_uv=False)
            out.update(twist_shear=shear, twist_singular_bound=low, twist_min_singular=float(sv[:, -1].min()),
                       twist_max_singular=float(sv[:, 0].max()))
            passed = passed and sv[:, -1].min() >= low * (1 - BOUND_TOL) and sv[:, 0].max() <= (1 / low) * (1 + BOUND_TOL)
            J = JT @ J
        out["min_singular"] = float(np.linalg.svd(J, compute_uv=False)[:, -1].min())
        passed = passed and out["min_singular"] >= bound * (1 - BOUND_TOL)
    elif twist is not None:
        out["twist_shear"] = shear
    return dict(out, passed=bool(passed))


__all__ = ["TWIST_KEYS", "TWIST_RIDGE", "TWIST_TERMS", "apply", "block_pull", "check", "fit_composite", "jacobian",
           "maps_of", "pulled_back", "twist_of", "z_units"]

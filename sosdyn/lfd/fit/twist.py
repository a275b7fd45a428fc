"""A twist about the goal: a rotation in a plane by an angle that depends on the distance to the goal.

In CDSP's z-units (goal 0), with an orthonormal pair p, q of R^n (the plane; for n = 2 the whole
space) and the angle

    alpha(r) = sum_j a_j (1 - exp(-r^2 / tau_j^2)),          r = |z|,

the twist is T(z) = R(alpha(|z|)) z with R(a) = I + (cos a - 1) P + sin a S, P = p p^T + q q^T,
S = q p^T - p q^T (R(a) = exp(a S): a rotation by a in the plane, from p towards q).

*A diffeomorphism fixing the goal.* alpha is a smooth function of |z|^2, so T is smooth; R is
orthogonal, so |T(z)| = |z|, and T^{-1}(u) = R(-alpha(|u|)) u is smooth too; T(0) = 0.

*Its Jacobian.* With beta(r) = alpha'(r) / r = sum_j a_j (2 / tau_j^2) exp(-r^2 / tau_j^2) (smooth
in |z|^2) and dR/da = R S,

    J_T(z) = R(alpha) (I + beta (S z) z^T),     J_T(z)^{-1} = (I - beta (S z) z^T) R(alpha)^T,

since z^T S z = 0 ((S z) z^T is nilpotent). det J_T = 1. On span(z, S z) the factor
I + beta (S z) z^T is [[1, 0], [k, 1]] in the orthonormal frame (z/|z|, S z/|S z|), with
k = beta |S z| |z|, and the identity elsewhere, so its singular values are 1/lam(|k|) and lam(|k|),
lam(k) = (k + sqrt(k^2 + 4)) / 2. Since |S z| <= |z| and 2 x e^{-x} <= 2/e,

    |k| <= |r alpha'(r)| <= K = (2/e) sum_j |a_j|,   so   1/lam(K) <= sigma(J_T(z)) <= lam(K)   for all z

(:func:`singular_bound`: 1/lam(K)). Composed after the bump warp B (u = T(B(z)), :mod:`.warp`):
prod_j (1 - l_j) / lam(K) <= sigma_min(J_{T o B}).

*Fit* (:func:`fit_twist`): the plane is the dominant 2-plane of the curves' angular momentum
sum_i (w_i dw_i^T - dw_i w_i^T) (for n = 2 the whole plane); along each curve (points w_i, in the
coordinates the twist acts on) the unwrapped angle theta_i in that plane; alpha is the least-squares
solution of theta_i + alpha(r_i) = c_d (one constant per curve: the twist unwinds the curves onto
rays from the goal), weighted by r_i / max r (the angle of a point near the goal means little),
with a ridge of weight ``ridge`` on the amplitudes; the widths tau_j are ``n_terms`` values
geometric between TAU_RANGE times the curves' largest r. The amplitudes are then scaled down, if
needed, so that K <= ``max_shear``.
"""
from __future__ import annotations

import math

import numpy as np

from sosdyn.errors import InputError

TAU_RANGE = (0.05, 2.0)         # the widths tau_j, relative to the curves' largest distance to the goal
PLANE_TOL = 1e-9                # |p.q|, |p| - 1, |q| - 1 accepted in a stored plane
MAX_TERMS = 64                  # terms of one twist, fitted or loaded
SHEAR_FACTOR = 2.0 / math.e     # sup_x 2 x exp(-x): |r alpha'(r)| <= SHEAR_FACTOR sum |a_j|
RIDGE_STEPS = 40                # bisection steps on the ridge weight that meets max_shear
MAX_SHEAR = 1e6                 # the largest K a stored twist may have (sigma_min(J_T) >= 1/lam(K) ~ 1/K)


def shear_bound(amplitudes) -> float:
    """K = (2/e) sum_j |a_j| >= sup_z |r alpha'(r)|."""
    return SHEAR_FACTOR * float(np.sum(np.abs(np.asarray(amplitudes, dtype=float))))


def singular_bound(amplitudes) -> float:
    """1 / lam(K) = 2 / (K + sqrt(K^2 + 4)) <= sigma_min(J_T(z)) for every z (module docstring)."""
    k = shear_bound(amplitudes)
    return 2.0 / (k + math.sqrt(k * k + 4.0))


def check_twist(plane, amplitudes, widths, *, what: str = "twist") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The twist's arrays as floats, checked: plane (2, n) with orthonormal rows (to PLANE_TOL),
    amplitudes and widths (m,), finite, widths > 0, m <= MAX_TERMS and K <= MAX_SHEAR. InputError
    naming the first violation."""
    P, a, tau = (np.asarray(x, dtype=float) for x in (plane, amplitudes, widths))
    if P.ndim != 2 or P.shape[0] != 2 or a.ndim != 1 or tau.shape != a.shape:
        raise InputError(f"{what}: plane {P.shape}, amplitudes {a.shape} and widths {tau.shape} must have shapes "
                         "(2, n), (m,) and (m,). Try: arrays from fit_twist.")
    if not all(np.isfinite(x).all() for x in (P, a, tau)) or not (tau > 0).all():
        raise InputError(f"{what}: every number must be finite and every width > 0. Try: arrays from fit_twist.")
    if len(a) > MAX_TERMS:
        raise InputError(f"{what}: {len(a)} terms, more than {MAX_TERMS}. Try: at most {MAX_TERMS} terms.")
    gram = P @ P.T
    if np.abs(gram - np.eye(2)).max() > PLANE_TOL:
        raise InputError(f"{what}: the plane's rows are not orthonormal (P P^T - I up to "
                         f"{np.abs(gram - np.eye(2)).max():.3g} > {PLANE_TOL:g}). Try: arrays from fit_twist.")
    if shear_bound(a) > MAX_SHEAR:
        raise InputError(f"{what}: K = (2/e) sum |a_j| = {shear_bound(a):.6g} > {MAX_SHEAR:g}: J_T may be too "
                         "ill-conditioned. Try: a smaller max_shear in fit_twist.")
    return P, a, tau


def angle(r2: np.ndarray, amplitudes, widths) -> tuple[np.ndarray, np.ndarray]:
    """(alpha, beta) at squared radii r2 (k,): alpha(r) and beta = alpha'(r) / r. The amplitudes and
    widths (m,), or (k, m): one twist per row."""
    a, tau2 = np.asarray(amplitudes, dtype=float), np.asarray(widths, dtype=float) ** 2
    e = np.exp(-np.asarray(r2, dtype=float)[..., None] / tau2)
    return (a * (1.0 - e)).sum(axis=-1), (a * (2.0 / tau2) * e).sum(axis=-1)


def _coords(W: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """(p.w, q.w) at the rows of W: (k, 2); ``plane`` (2, n), or (k, 2, n) per row."""
    return W @ plane.T if plane.ndim == 2 else np.einsum("kn,kjn->kj", W, plane)


def _span(c: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """c_0 p + c_1 q at the rows of c (k, 2): (k, n)."""
    return c @ plane if plane.ndim == 2 else np.einsum("kj,kjn->kn", c, plane)


def _turn(W: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """S w = (p.w) q - (q.w) p at the rows of W."""
    c = _coords(W, plane)
    return _span(np.column_stack([-c[:, 1], c[:, 0]]), plane)


def _rotate(W: np.ndarray, plane: np.ndarray, cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
    """R(a) w at the rows of W, cos a and sin a per row: w + (cos - 1) P w + sin S w."""
    c = _coords(W, plane)
    return W + _span((cos - 1.0)[:, None] * c + sin[:, None] * np.column_stack([-c[:, 1], c[:, 0]]), plane)


def apply(W, plane, amplitudes, widths) -> np.ndarray:
    """T(W) at the rows of W (k, n)."""
    W = np.asarray(W, dtype=float)
    a, _ = angle(np.sum(W * W, axis=1), amplitudes, widths)
    return _rotate(W, np.asarray(plane, dtype=float), np.cos(a), np.sin(a))


def invert(U, plane, amplitudes, widths) -> np.ndarray:
    """T^{-1}(U) = R(-alpha(|u|)) u at the rows of U (k, n)."""
    U = np.asarray(U, dtype=float)
    a, _ = angle(np.sum(U * U, axis=1), amplitudes, widths)
    return _rotate(U, np.asarray(plane, dtype=float), np.cos(a), -np.sin(a))


def jacobian(W, plane, amplitudes, widths) -> tuple[np.ndarray, np.ndarray]:
    """(T(W), J_T(W)): (k, n) and (k, n, n), J_T = R(alpha) (I + beta (S w) w^T), column by column."""
    W, P = np.asarray(W, dtype=float), np.asarray(plane, dtype=float)
    k, n = W.shape
    a, b = angle(np.sum(W * W, axis=1), amplitudes, widths)
    cos, sin = np.cos(a), np.sin(a)
    inner = np.eye(n)[None] + b[:, None, None] * _turn(W, P)[:, :, None] * W[:, None, :]
    J = np.stack([_rotate(inner[:, :, j], P, cos, sin) for j in range(n)], axis=2)
    return _rotate(W, P, cos, sin), J


def pulled_back(W, plane, amplitudes, widths, field) -> np.ndarray:
    """J_T(w)^{-1} field(T(w)) at the rows of W (k, n): y = R^T field(T(w)), then y - beta (w.y) S w.
    One twist, or one per row (plane (k, 2, n), amplitudes and widths (k, m))."""
    W, P = np.asarray(W, dtype=float), np.asarray(plane, dtype=float)
    a, b = angle(np.sum(W * W, axis=1), amplitudes, widths)
    cos, sin = np.cos(a), np.sin(a)
    Y = _rotate(np.asarray(field(_rotate(W, P, cos, sin)), dtype=float), P, cos, -sin)
    return Y - np.sum((b[:, None] * W) * Y, axis=1)[:, None] * _turn(W, P)     # beta w first: 0, not 0 * inf, far out


def fit_plane(curves: list[np.ndarray]) -> np.ndarray:
    """The dominant 2-plane (2, n), orthonormal rows, of sum_i (w_i dw_i^T - dw_i w_i^T) over the curves'
    points and steps (the identity's rows for n = 2)."""
    n = curves[0].shape[1]
    if n == 2:
        return np.eye(2)
    L = np.zeros((n, n))
    for w in curves:
        d = np.diff(w, axis=0)
        m = 0.5 * (w[1:] + w[:-1])
        L += m.T @ d - d.T @ m
    U, _, Vt = np.linalg.svd(L)
    # L v = s u with u orthogonal to v (L skew): the plane of (U[:, 0], Vt[0]); orthonormalised by QR, which
    # also gives an orthonormal pair when L = 0 (curves without rotation: then any plane will do)
    Q = np.linalg.qr(np.column_stack([U[:, 0], Vt[0], np.eye(n)]))[0]
    return Q[:, :2].T


def fit_twist(curves: list[np.ndarray], n_terms: int, ridge: float, max_shear: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(plane, amplitudes, widths) unwinding ``curves`` [(N, n)] (module docstring)."""
    plane = fit_plane(curves)
    scale = max(float(np.linalg.norm(w, axis=1).max()) for w in curves) or 1.0
    widths = scale * np.geomspace(*TAU_RANGE, n_terms)
    rows, cols, target, weight = [], [], [], []
    for d, w in enumerate(curves):
        c = w @ plane.T
        r = np.linalg.norm(w, axis=1)
        keep = np.hypot(c[:, 0], c[:, 1]) > 1e-9 * scale
        theta = np.unwrap(np.arctan2(c[keep, 1], c[keep, 0]))
        basis = 1.0 - np.exp(-r[keep, None] ** 2 / widths ** 2)
        one = np.zeros((keep.sum(), len(curves)))
        one[:, d] = -1.0
        rows.append(np.hstack([basis, one]))
        target.append(-theta)
        weight.append(r[keep] / scale)
    sw = np.concatenate(weight)
    A, y = np.vstack(rows) * sw[:, None], np.concatenate(target) * sw
    a = _ridge_solve(A, y, n_terms, ridge)
    if shear_bound(a) > max_shear:                  # the least ridge with K <= max_shear (K falls as it grows)
        lo, hi = ridge, max(ridge, 1e-12)
        while shear_bound(_ridge_solve(A, y, n_terms, hi)) > max_shear:
            lo, hi = hi, hi * 10.0
        for _ in range(RIDGE_STEPS):
            mid = math.sqrt(max(lo, 1e-300) * hi) if lo > 0 else hi / 10.0
            lo, hi = (mid, hi) if shear_bound(_ridge_solve(A, y, n_terms, mid)) > max_shear else (lo, mid)
        a = _ridge_solve(A, y, n_terms, hi)
    return plane, a, widths


def _ridge_solve(A, y, n_terms: int, ridge: float) -> np.ndarray:
    """The amplitudes of argmin |A x - y|^2 + ridge |x[:n_terms]|^2."""
    reg = math.sqrt(ridge) * np.hstack([np.eye(n_terms), np.zeros((n_terms, A.shape[1] - n_terms))])
    return np.linalg.lstsq(np.vstack([A, reg]), np.concatenate([y, np.zeros(n_terms)]), rcond=None)[0][:n_terms]


def check_sampled(plane, amplitudes, widths, Z: np.ndarray) -> dict:
    """At the rows of Z: the smallest and largest singular values of J_T against the closed-form
    bounds 1/lam(K) and lam(K) (module docstring)."""
    sv = np.linalg.svd(jacobian(Z, plane, amplitudes, widths)[1], compute_uv=False)
    low = singular_bound(amplitudes)
    return {"shear_bound": shear_bound(amplitudes), "singular_bound": low, "min_singular": float(sv[:, -1].min()),
            "max_singular": float(sv[:, 0].max())}


__all__ = ["MAX_SHEAR", "MAX_TERMS", "PLANE_TOL", "SHEAR_FACTOR", "TAU_RANGE", "angle", "apply", "check_sampled",
           "check_twist", "fit_plane", "fit_twist", "invert", "jacobian", "pulled_back", "shear_bound",
           "singular_bound"]

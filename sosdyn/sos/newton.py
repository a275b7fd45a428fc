"""Gram-basis selection by the Newton polytope.

If p = sum_i q_i^2 then every monomial x^a of every q_i satisfies 2a in N(p), the convex
hull of p's exponents (Reznick 1978). We keep the half-degree candidates a with
ceil(min deg/2) <= |a| <= floor(max deg/2) and 2a in N(p); the hull test works in the
affine hull of the support (a homogeneous p has a lower-dimensional Newton polytope), by
Qhull's facets up to :data:`HULL_MAX_DIM` dimensions and above that by one small LP per
candidate (find lambda >= 0, sum lambda = 1, S^T lambda = point; Qhull's facet count explodes
with the dimension: chained Rosenbrock in 22 variables did not finish in 20 s).

A basis that misses a monomial some Gram matrix needs makes a feasible program infeasible, so
the facets are trusted only after a self-check. Every facet row h, b is linear in the point, so
for p = sum_j lambda_j s_j in conv(S), h.p + b = sum_j lambda_j (h.s_j + b) <= max_j (h.s_j + b):
if every support point passes the facet test, every point of the hull passes it too. When Qhull
fails (a degenerate support: chained Rosenbrock in 12 variables has a "flat initial simplex")
or a support point tests outside its own hull, membership falls back to the LPs, and an LP that
ends without a verdict keeps its monomial (an extra monomial only enlarges the Gram matrix).

The basis is checked against ``sosdyn.limits`` (max_bytes) before it is returned: coefficient
matching over a basis of b monomials builds arrays over all s = b(b+1)/2 pairs
(:func:`gram_matching_bytes`), so a basis too large to match is refused before the Gram
matching allocates anything.
"""
from __future__ import annotations

import functools

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from ..limits import check_bytes
from ..poly.monomials import match_rows, monomials_up_to

HULL_MAX_DIM = 12    # above this affine dimension, hull membership by LP instead of Qhull


def in_hull_lp(points: np.ndarray, support: np.ndarray) -> np.ndarray:
    """Boolean mask: which rows of ``points`` are convex combinations of rows of ``support`` (LPs)."""
    S = support.astype(float)
    A = np.vstack([S.T, np.ones((1, S.shape[0]))])
    inside = match_rows(np.unique(support, axis=0), points) >= 0
    for k in np.flatnonzero(~inside):
        res = linprog(np.zeros(S.shape[0]), A_eq=A, b_eq=np.append(points[k].astype(float), 1.0),
                      bounds=(0, None), method="highs")
        inside[k] = res.status != 2        # dropped only when the LP proves it infeasible
    return inside


def in_hull(points: np.ndarray, support: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Boolean mask: which rows of ``points`` lie in conv(rows of ``support``)."""
    S = support.astype(float)
    P = points.astype(float)
    center = S.mean(axis=0)
    _, sing, vt = np.linalg.svd(S - center, full_matrices=False)
    rank = int((sing > 1e-9 * max(1.0, sing.max(initial=0.0))).sum())
    basis = vt[:rank]
    DP = P - center
    coords = DP @ basis.T
    off_plane = np.linalg.norm(DP - coords @ basis, axis=1) > tol * (1 + np.abs(P).max(initial=0))
    if rank == 0:
        return ~off_plane
    ys = (S - center) @ basis.T
    if rank > HULL_MAX_DIM:
        return ~off_plane & in_hull_lp(points, support)
    if rank == 1:
        lo, hi = ys.min() - tol, ys.max() + tol
        return ~off_plane & (coords[:, 0] >= lo) & (coords[:, 0] <= hi)
    try:
        eq = ConvexHull(ys).equations
    except QhullError:  # a degenerate support Qhull cannot start on: decide by LPs
        return ~off_plane & in_hull_lp(points, support)
    margin = tol * (1 + np.abs(ys).max())
    if (ys @ eq[:, :-1].T + eq[:, -1] > margin).any():  # a support point outside its own hull
        return ~off_plane & in_hull_lp(points, support)
    inside = (coords @ eq[:, :-1].T + eq[:, -1] <= margin).all(axis=1)
    return ~off_plane & inside


def gram_matching_bytes(b: int, n: int) -> float:
    """Bytes of matching coefficients over a Gram basis of b monomials in n variables.

    s = b(b+1)/2 pairs: their exponent sums (s x n int64) and a sorted copy, plus about
    twelve length-s arrays (svec pairs, sort keys, order, inverse, weights, the sparse
    map's indices and values, the matching rows).
    """
    return 8.0 * b * (b + 1) / 2 * (2 * n + 12)


CACHE_MAX_TERMS = 256   # newton_basis keeps its answers for supports up to this many terms


def newton_basis(support: np.ndarray) -> np.ndarray:
    """Half-degree monomials whose doubles lie in the Newton polytope of ``support``.

    ``support`` is the (m, n) exponent array of the polynomial's monomials. Returns the
    basis exponents (graded order, read-only: answers for small supports are cached); an
    empty support gives an empty basis.
    """
    support = np.ascontiguousarray(support, dtype=np.int64)
    n = support.shape[1]
    if support.shape[0] <= CACHE_MAX_TERMS:
        basis = _newton_basis_cached(support.shape, support.tobytes())
    else:
        basis = _newton_basis(support)
    check_bytes(gram_matching_bytes(basis.shape[0], n),
                f"coefficient matching over a Gram basis of {basis.shape[0]} monomials in {n} variables",
                "lower the degree, use sparsity='correlative' or 'term' in add_sos/add_nonneg_on "
                "(one smaller Gram block per clique or term component), or split the polynomial into "
                "parts in fewer variables")
    return basis


def _newton_basis(support: np.ndarray) -> np.ndarray:
    n = support.shape[1]
    if support.shape[0] == 0:
        basis = np.zeros((0, n), dtype=np.int64)
    else:
        deg = support.sum(axis=1)
        lo, hi = int(np.ceil(deg.min() / 2)), int(deg.max() // 2)
        cand = monomials_up_to(n, hi, lo, max_per_var=support.max(axis=0) // 2)
        basis = cand[(2 * cand >= support.min(axis=0)).all(axis=1)]
        if basis.shape[0] and n:
            basis = basis[in_hull(2 * basis, support)]
    basis.flags.writeable = False
    return basis


@functools.lru_cache(maxsize=512)
def _newton_basis_cached(shape: tuple, data: bytes) -> np.ndarray:
    return _newton_basis(np.frombuffer(data, dtype=np.int64).reshape(shape))

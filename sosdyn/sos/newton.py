"""Gram-basis selection by the Newton polytope.

If p = sum_i q_i^2 then every monomial x^a of every q_i satisfies 2a in N(p), the convex
hull of p's exponents (Reznick 1978). We keep the half-degree candidates a with
ceil(min deg/2) <= |a| <= floor(max deg/2) and 2a in N(p); the hull test works in the
affine hull of the support (a homogeneous p has a lower-dimensional Newton polytope).

The basis is checked against ``sosdyn.limits`` (max_bytes) before it is returned: coefficient
matching over a basis of b monomials builds arrays over all s = b(b+1)/2 pairs
(:func:`gram_matching_bytes`), so a basis too large to match is refused before the Gram
matching allocates anything.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from ..limits import check_bytes
from ..poly.monomials import monomials_up_to


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
    if rank == 1:
        lo, hi = ys.min() - tol, ys.max() + tol
        return ~off_plane & (coords[:, 0] >= lo) & (coords[:, 0] <= hi)
    try:
        eq = ConvexHull(ys).equations
    except QhullError:  # degenerate after projection: fall back to joggled input
        eq = ConvexHull(ys, qhull_options="QJ").equations
    inside = (coords @ eq[:, :-1].T + eq[:, -1] <= tol * (1 + np.abs(ys).max())).all(axis=1)
    return ~off_plane & inside


def gram_matching_bytes(b: int, n: int) -> float:
    """Bytes of matching coefficients over a Gram basis of b monomials in n variables.

    s = b(b+1)/2 pairs: their exponent sums (s x n int64) and a sorted copy, plus about
    twelve length-s arrays (svec pairs, sort keys, order, inverse, weights, the sparse
    map's indices and values, the matching rows).
    """
    return 8.0 * b * (b + 1) / 2 * (2 * n + 12)


def newton_basis(support: np.ndarray) -> np.ndarray:
    """Half-degree monomials whose doubles lie in the Newton polytope of ``support``.

    ``support`` is the (m, n) exponent array of the polynomial's monomials. Returns the
    basis exponents (graded order); an empty support gives an empty basis.
    """
    n = support.shape[1]
    if support.shape[0] == 0:
        return np.zeros((0, n), dtype=np.int64)
    deg = support.sum(axis=1)
    lo, hi = int(np.ceil(deg.min() / 2)), int(deg.max() // 2)
    cand = monomials_up_to(n, hi, lo, max_per_var=support.max(axis=0) // 2)
    cand = cand[(2 * cand >= support.min(axis=0)).all(axis=1)]
    if cand.shape[0] == 0 or n == 0:
        return cand
    basis = cand[in_hull(2 * cand, support)]
    check_bytes(gram_matching_bytes(basis.shape[0], n),
                f"coefficient matching over a Gram basis of {basis.shape[0]} monomials in {n} variables",
                "lower the degree or the number of variables, or split the polynomial into parts in "
                "fewer variables")
    return basis

"""Gram matrices: the svec layout and the sparse coefficient-matching map.

A Gram matrix Q (size b) over the basis z(x) is stored as its scaled upper triangle,
column by column (Clarabel's PSD-triangle layout): s = (Q_00, sqrt2 Q_01, Q_11,
sqrt2 Q_02, ...). Then z^T Q z = sum_k w_k s_k x^(a_i + a_j) with w = 1 on the diagonal
and sqrt2 off it; grouping equal exponent sums (np.unique) gives one sparse matrix
G (monomials x svec) with coefficient(z^T Q z) = G s.

Exact arithmetic, for rigorous bounds: every float is a dyadic rational, so a numerical
Gram matrix can be read exactly (``exact_gram``: Q_ij = s_k SQRT2 / 2 with the float SQRT2,
the convention of every polynomial built on a block), a residual e = p - z^T Q z absorbed
exactly (``absorb_residual``: the orthogonal projection of Q onto {Q : z^T Q z = p}, which
spreads each coefficient of e evenly over the Gram entries producing its monomial), and a
rational matrix proven positive semidefinite (``proven_min_eig``: round to a grid of
step h, then Q = h N + R with |R_ij| <= h/2, so lambda_min(Q) >= lambda_min(h N) - n h / 2;
N - k I > 0 for an integer k > n/2 is decided exactly by Sylvester's criterion, all leading
principal minors positive, computed fraction-free by Bareiss elimination). A matrix that
is singular exactly (structure forced by the data, no interior) is proven PSD by exact
rational LDL^T instead: a zero pivot must come with a zero row.
"""
from __future__ import annotations

import functools
import math
from fractions import Fraction

import numpy as np
import scipy.linalg as sla

from ..poly.monomials import unique_rows

SQRT2 = np.sqrt(2.0)


def svec_pairs(b: int):
    """Row and column index (i <= j) of every svec entry, in Clarabel's order (read-only arrays:
    answers are cached, every Gram block of a size asks for the same)."""
    return _svec_pairs(int(b))


@functools.lru_cache(maxsize=256)
def _svec_pairs(b: int):
    cols = np.repeat(np.arange(b), np.arange(1, b + 1))
    rows = np.concatenate([np.arange(j + 1) for j in range(b)]) if b else np.zeros(0, dtype=int)
    out = rows.astype(np.int64), cols.astype(np.int64)
    for a in out:
        a.flags.writeable = False
    return out


def svec_size(b: int) -> int:
    return b * (b + 1) // 2


def svec_to_matrix(s: np.ndarray, b: int) -> np.ndarray:
    """The symmetric matrix of an svec vector."""
    i, j = svec_pairs(b)
    Q = np.zeros((b, b))
    vals = np.where(i == j, s, s / SQRT2)
    Q[i, j] = vals
    Q[j, i] = vals
    return Q


def matrix_to_svec(Q: np.ndarray) -> np.ndarray:
    i, j = svec_pairs(Q.shape[0])
    return np.where(i == j, Q[i, j], SQRT2 * Q[i, j])


CACHE_MAX_BASIS = 64  # gram_matching keeps its answers for bases up to this size (small, often repeated)


def gram_matching(basis: np.ndarray):
    """Monomials of z^T Q z and the sparse map G with coefficients = G @ svec(Q).

    Returns (exps, rows, weights): svec entry k adds weights[k] s_k to the coefficient of
    monomial exps[rows[k]], i.e. G has one entry (rows[k], k) per column. The arrays are
    read-only: answers for small bases are cached (a program repeats its bases).
    """
    basis = np.ascontiguousarray(basis, dtype=np.int64)
    if basis.shape[0] <= CACHE_MAX_BASIS:
        return _gram_matching_cached(basis.shape, basis.tobytes())
    return _gram_matching(basis)


def _gram_matching(basis: np.ndarray):
    i, j = svec_pairs(basis.shape[0])
    pairs = basis[i]
    pairs += basis[j]                  # in place: two (pairs x variables) arrays at most
    exps, rows = unique_rows(pairs)
    out = (exps, rows, np.where(i == j, 1.0, SQRT2))
    for a in out:
        a.flags.writeable = False
    return out


@functools.lru_cache(maxsize=512)
def _gram_matching_cached(shape: tuple, data: bytes):
    return _gram_matching(np.frombuffer(data, dtype=np.int64).reshape(shape))


# ---------------------------------------------------------------------- exact arithmetic
GRID_BITS = 48       # proven_min_eig rounds to max|Q| * 2^-48 before the exact test
EXACT_LDL_MAX = 64   # largest block tried by the exact rational LDL^T (singular blocks)


def exact_gram(s, b: int) -> np.ndarray:
    """The symmetric Gram matrix of svec values ``s`` (floats or Fractions), exactly."""
    i, j = svec_pairs(b)
    half = Fraction(SQRT2) / 2
    Q = np.empty((b, b), dtype=object)
    for k, (a, c) in enumerate(zip(i, j)):
        v = s[k] if isinstance(s[k], Fraction) else Fraction(float(s[k]))
        Q[a, c] = Q[c, a] = v * (1 if a == c else half)
    return Q


def gram_form(basis: np.ndarray, Q: np.ndarray) -> dict:
    """Coefficients of z^T Q z as {exponent tuple: value} (exact for Fraction entries)."""
    out: dict = {}
    b = basis.shape[0]
    for i in range(b):
        for j in range(i, b):
            if Q[i, j]:
                m = tuple(int(v) for v in basis[i] + basis[j])
                out[m] = out.get(m, 0) + (Q[i, j] if i == j else 2 * Q[i, j])
    return out


def absorb_residual(basis: np.ndarray, Q: np.ndarray, residual: dict):
    """Q + E with z^T E z = residual, each coefficient spread evenly over its Gram slots.

    Returns (Q + E, None), or (None, exponent) for a residual monomial no product z_i z_j
    produces (then no Gram matrix over this basis matches the polynomial).
    """
    slots: dict = {}
    b = basis.shape[0]
    for i in range(b):
        for j in range(b):
            slots.setdefault(tuple(int(v) for v in basis[i] + basis[j]), []).append((i, j))
    out = Q.copy()
    for m, c in residual.items():
        if not c:
            continue
        if m not in slots:
            return None, m
        share = c / len(slots[m])
        for i, j in slots[m]:
            out[i, j] += share
    return out, None


def positive_definite_int(A: np.ndarray) -> bool:
    """Exact test that a symmetric integer matrix is positive definite (module docstring)."""
    M = np.array(A, dtype=object)
    prev = 1
    for k in range(M.shape[0]):
        pivot = M[k, k]                 # = det of the leading (k+1) x (k+1) block
        if pivot <= 0:
            return False
        if k + 1 < M.shape[0]:
            M[k + 1:, k + 1:] = (M[k + 1:, k + 1:] * pivot - np.outer(M[k + 1:, k], M[k, k + 1:])) // prev
        prev = pivot
    return True


def exactly_psd(Q: np.ndarray) -> bool:
    """Exact PSD test of a rational symmetric matrix by LDL^T (zero pivots allowed, zero rows)."""
    A = [[Fraction(v) for v in row] for row in Q]
    n = len(A)
    for k in range(n):
        pivot = A[k][k]
        if pivot < 0 or (pivot == 0 and any(A[k][j] != 0 for j in range(k + 1, n))):
            return False
        if pivot == 0:
            continue
        for i in range(k + 1, n):
            if A[i][k] != 0:
                f = A[i][k] / pivot
                for j in range(k + 1, n):
                    A[i][j] -= f * A[k][j]
    return True


def float_down(q: Fraction) -> float:
    """The largest float <= q."""
    f = float(q)
    return f if Fraction(f) <= q else math.nextafter(f, -math.inf)


def proven_min_eig(Q: np.ndarray):
    """A proven lower bound >= 0 on lambda_min of a rational symmetric matrix, or None.

    None means positive semidefiniteness could not be proven (module docstring); a matrix
    proven PSD only by the exact LDL^T test (size <= EXACT_LDL_MAX) gets bound 0.
    """
    n = Q.shape[0]
    if n == 0:
        return math.inf
    Qf = np.vectorize(float, otypes=[float])(Q)
    top = float(np.abs(Qf).max())
    if top == 0.0:
        return 0.0 if all(v == 0 for v in Q.flat) else None
    h = Fraction(2) ** (math.frexp(top)[1] - GRID_BITS)
    N = np.vectorize(lambda v: round(v / h), otypes=[object])(Q)
    k_min = n // 2 + 1
    estimate = float(np.linalg.eigvalsh(Qf)[0]) / float(h) if float(h) else 0.0   # in units of h
    for k in sorted({k_min, max(k_min, int(estimate / 2)), max(k_min, int(estimate * 0.999))}, reverse=True):
        if positive_definite_int(N - k * np.eye(n, dtype=np.int64).astype(object)):
            return float_down(h * (k - Fraction(n, 2)))
    return 0.0 if n <= EXACT_LDL_MAX and exactly_psd(Q) else None


def exact(v) -> Fraction:
    """A float (or Fraction) as an exact Fraction."""
    return v if isinstance(v, Fraction) else Fraction(float(v))


# An exact polynomial affine in the decisions is {exponent tuple: [constant, {id: coef}]}.
def exact_affine(p, scale=Fraction(1), shift=None) -> dict:
    """scale * x^shift * p for a Polynomial p, as an exact affine map (see above)."""
    out: dict = {}
    for r in range(p.nterms):
        e = p.exps[r] if shift is None else p.exps[r] + shift
        entry = out.setdefault(tuple(int(a) for a in e), [Fraction(0), {}])
        entry[0] += scale * exact(p.coef[r, 0])
        for c in np.flatnonzero(p.coef[r, 1:]):
            d = int(p.ids[c])
            entry[1][d] = entry[1].get(d, 0) + scale * exact(p.coef[r, 1 + c])
    return out


def merge_affine(into: dict, part: dict) -> dict:
    """into += part, for exact affine maps."""
    for m, (c, lin) in part.items():
        entry = into.setdefault(m, [Fraction(0), {}])
        entry[0] += c
        for d, v in lin.items():
            entry[1][d] = entry[1].get(d, 0) + v
    return into


def evaluate_affine(affine: dict, values: dict) -> dict:
    """The exact polynomial {exponent: value} of an affine map at decision ``values``."""
    out = {}
    for m, (c, lin) in affine.items():
        v = c + sum((a * values[d] for d, a in lin.items()), Fraction(0))
        if v:
            out[m] = v
    return out


def exact_sub(a: dict, b: dict) -> dict:
    """a - b for exact polynomials {exponent: value}."""
    out = dict(a)
    for m, c in b.items():
        out[m] = out.get(m, 0) - c
    return {m: c for m, c in out.items() if c}


def _solve_exact(G: list, r: list):
    """A solution y of G y = r (G square, exact, possibly singular), or None if inconsistent."""
    k = len(r)
    A = [row[:] + [r[i]] for i, row in enumerate(G)]
    pivots, row = [], 0
    for col in range(k):
        piv = next((i for i in range(row, k) if A[i][col] != 0), None)
        if piv is None:
            continue
        A[row], A[piv] = A[piv], A[row]
        inv = 1 / A[row][col]
        A[row] = [v * inv for v in A[row]]
        for i in range(k):
            if i != row and A[i][col] != 0:
                f = A[i][col]
                A[i] = [a - f * b for a, b in zip(A[i], A[row])]
        pivots.append(col)
        row += 1
    if any(A[i][k] != 0 for i in range(row, k)):
        return None
    y = [Fraction(0)] * k
    for i, col in enumerate(pivots):
        y[col] = A[i][k]
    return y


def exact_correction(rows: list, values: dict):
    """The minimum-norm exact change of the decisions that makes every row hold.

    ``rows``: (constant, {id: coef}) meaning constant + sum coef d = 0, i.e. A d = b; the
    change is A^T y with (A A^T) y = b - A d. Returns {id: change} (empty when every row
    holds already) or None when the rows are inconsistent.
    """
    resid = [-(c + sum((a * values[d] for d, a in lin.items()), Fraction(0))) for c, lin in rows]
    if not any(resid):
        return {}
    G = [[sum((a * lj.get(d, 0) for d, a in li.items()), Fraction(0)) for _, lj in rows] for _, li in rows]
    y = _solve_exact(G, resid)
    if y is None:
        return None
    delta: dict = {}
    for yi, (_, lin) in zip(y, rows):
        if yi:
            for d, a in lin.items():
                delta[d] = delta.get(d, 0) + a * yi
    return delta


def exact_solution(rows, start: dict, avoid=()):
    """The exact change of the unknowns that makes every row c + sum a u = 0 hold, or None.

    Independent rows and as many well-conditioned unknowns are chosen in floating point (QR with
    column pivoting), the square system on them solved in rational arithmetic by sparse
    elimination (the rows of a coefficient matching touch few unknowns), and every row then
    checked exactly: a row the floats called dependent but that does not hold means the system is
    inconsistent. Unknowns in ``avoid`` (the objective's) are chosen last: the correction moves the
    certificate, not the bound, where it can."""
    keys = sorted({u for _, lin in rows for u in lin}, key=repr)
    col = {u: k for k, u in enumerate(keys)}
    r = [-(c + sum((a * start[u] for u, a in lin.items()), Fraction(0))) for c, lin in rows]
    if not any(r):
        return {}
    A = np.zeros((len(rows), len(keys)))
    for i, (_, lin) in enumerate(rows):
        for u, a in lin.items():
            A[i, col[u]] = float(a)
    _, Rr, prow = sla.qr(A.T, mode="economic", pivoting=True)
    d = np.abs(np.diag(Rr))
    rank = int((d > 1e-10 * max(d.max(initial=0.0), 1e-300)).sum())
    use = prow[:rank]
    weight = np.array([1e-8 if u in set(avoid) else 1.0 for u in keys])
    _, _, pcol = sla.qr(A[use] * weight, mode="economic", pivoting=True)
    chosen = [keys[k] for k in pcol[:rank]]
    system = [({u: a for u, a in rows[i][1].items() if u in set(chosen)}, r[i]) for i in use]
    solved = _eliminate(system, chosen)
    if solved is None:
        return None
    values = {u: start[u] + solved.get(u, 0) for u in start}
    if any(c + sum((a * values[u] for u, a in lin.items()), Fraction(0)) for c, lin in rows):
        return None
    return solved


def _eliminate(system, unknowns):
    """Solve the square sparse rational system [({unknown: a}, rhs)] for ``unknowns``, or None."""
    rows = [({u: a for u, a in lin.items() if a}, rhs) for lin, rhs in system]
    pivots = []
    for u in unknowns:
        cands = [k for k in range(len(pivots), len(rows)) if rows[k][0].get(u)]
        if not cands:
            return None
        k = max(cands, key=lambda k: (abs(float(rows[k][0][u])), -len(rows[k][0])))
        rows[len(pivots)], rows[k] = rows[k], rows[len(pivots)]
        plin, prhs = rows[len(pivots)]
        for j in range(len(pivots) + 1, len(rows)):
            lin, rhs = rows[j]
            f = lin.get(u)
            if f:
                f = f / plin[u]
                for v, a in plin.items():
                    w = lin.get(v, 0) - f * a
                    if w:
                        lin[v] = w
                    else:
                        lin.pop(v, None)
                rows[j] = (lin, rhs - f * prhs)
        pivots.append(u)
    out = {}
    for k in reversed(range(len(pivots))):
        lin, rhs = rows[k]
        u = pivots[k]
        out[u] = (rhs - sum((a * out[v] for v, a in lin.items() if v != u), Fraction(0))) / lin[u]
    return out

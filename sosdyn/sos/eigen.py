"""Proven eigenvalue bounds of float matrices, and the congruence the judge may prove them in.

:func:`eig_lower` bounds lambda_min of a float matrix from a Cholesky factor and its rounding
(Higham, *Accuracy and stability of numerical algorithms*, ch. 10); :func:`constant_need` is the
raise of one diagonal entry a matrix needs for a margin (a Schur complement).

**Balanced coordinates.** A Gram identity p = z^T (Q~ + E~) z (:mod:`.proof`, step 4) is equally
proven by any positive diagonal D: Q~ + E~ >= 0 iff D (Q~ + E~) D >= 0, which holds when
lambda_min(D Q~ D) >= ||D E~ D||_F. With D_ii = s^(b_i) for the basis monomial x^(b_i) -- the
change of variables x = s u -- every pair (i, j) giving x^a has D_ii D_jj = s^a, so
||D E~ D||_F^2 = sum_a s^(2a) e~_a^2 / N_a. When the solver's Gram matrix spans many orders of
magnitude (x^2 + 24 x^3 + 0.1 x^4: its minimiser -180, z = (1, x, x^2) of sizes 1 ... 3e4), its
kernel vector is tiny in the constant monomial and a margin on the constant costs
|z(x*)|^2 = 1e9 times the residual; with s = 2^k balancing the diagonal of D Q~ D
(:func:`balancing`) it costs a few times the residual. Powers of two make D Q~ D and s^a B_a
exact in floating point (:func:`congruent` refuses a scaling that would leave the normal range).
:func:`balanced_blocks` gives a face's blocks, margins and constant raises in those coordinates.
"""
from __future__ import annotations

import math

import numpy as np

from .gram import svec_pairs
from .identity import EPS, UNIT, gam


def down(v: float) -> float:
    """A float at most v (two steps towards -inf: v may itself be a rounded sum)."""
    return math.nextafter(math.nextafter(float(v), -math.inf), -math.inf)


def eig_lower(A: np.ndarray) -> float:
    """A proven lower bound on lambda_min(A) for a symmetric float matrix A (-inf if none).

    With t below the estimated lambda_min and L = chol(fl(A - tI)), A - tI = L L^T + R exactly,
    |R| <= |fl(A - tI - L L^T)| (1 + 2u) + gamma_(2n+4) |L||L|^T + u |diag(A - tI)| entrywise
    (the rounding of forming A - tI, of L L^T and of the subtraction), so lambda_min(A) >= t -
    ||R||_F, the norm itself rounded up."""
    n = A.shape[0]
    if n == 0:
        return math.inf
    if not np.isfinite(A).all():
        return -math.inf
    norm = float(np.linalg.norm(A))
    if norm == 0.0:
        return 0.0
    lam = float(np.linalg.eigvalsh(A)[0])
    slack = (n + 4) * EPS * norm
    diag = np.arange(n)
    for k in range(6):
        t = lam - slack * 8.0**k
        B = A.copy()
        B[diag, diag] -= t
        try:
            L = np.linalg.cholesky(B)
        except np.linalg.LinAlgError:
            continue
        aL = np.abs(L)
        err = np.abs(B - L @ L.T) * (1 + 2 * UNIT) + gam(2 * n + 4) * (aL @ aL.T)
        err[diag, diag] += UNIT * np.abs(np.diag(B))
        r = float(np.linalg.norm(err)) * (1 + float(gam(n * n + 4)))
        if np.isfinite(r):
            return down(t - r)
    return -math.inf


def constant_need(A, k0: int, tau: float) -> float:
    """The signed number c with lambda_min(A + d e_k0 e_k0^T) >= tau iff d >= c (up to rounding),
    or inf when no d works. With A' = A without row/column k0 and b = A[others, k0]: PSD iff
    A' - tau I > 0 and a_00 + d - tau >= b^T (A' - tau I)^{-1} b (Schur complement)."""
    rest = np.delete(np.arange(A.shape[0]), k0)
    Ar = A[np.ix_(rest, rest)] - tau * np.eye(rest.size)
    if rest.size and np.linalg.eigvalsh(Ar)[0] <= 8 * (rest.size + 4) * EPS * float(np.linalg.norm(A)):
        return math.inf
    b = A[rest, k0]
    return tau - A[k0, k0] + (float(b @ np.linalg.solve(Ar, b)) if rest.size else 0.0)


def balancing(A: np.ndarray, exps: np.ndarray) -> np.ndarray:
    """log2 of D's diagonal, b_i . k for the rows of A (basis exponents ``exps``), with the integer k
    (one per variable) that makes the diagonal of D A D most even: least squares on
    log2 A_ii + 2 b_i . k over the positive diagonal entries. Zeros when nothing is to gain."""
    d = np.diag(A)
    pos = d > 0
    if pos.sum() < 2 or not exps.size:
        return np.zeros(A.shape[0], dtype=np.int64)
    M = np.hstack([2.0 * exps[pos], np.ones((int(pos.sum()), 1))])
    k = np.rint(np.linalg.lstsq(M, -np.log2(d[pos]), rcond=None)[0][:-1]).astype(np.int64)
    return exps @ k


def congruent(A: np.ndarray, shift: np.ndarray) -> np.ndarray | None:
    """D A D for D = diag(2^shift), exact in floating point; None when an entry would overflow or
    fall below the normal range (where scaling by a power of two rounds)."""
    out = np.ldexp(A, shift[:, None] + shift[None, :])
    on = A != 0
    if not np.isfinite(out).all() or (np.abs(out[on]) < np.finfo(float).tiny).any():
        return None
    return out


def better_guide(balanced, plain) -> bool:
    """The balanced blocks guide the correction (:mod:`.posterior`) better: their constant entries
    need less in all (D_00 = 1: a raise is the same number in both coordinates), or no block has a
    constant row (the correction then bisects on D A D, better conditioned)."""
    if all(math.isnan(n) for n in plain):
        return True
    return sum(n for n in balanced if not math.isnan(n)) < sum(n for n in plain if not math.isnan(n))


def balanced_blocks(A, kept, block_exps, ident, grams, owner, N, bound, zero):
    """(D A D, its lam, tau, need, log2 D) per block for the balancing D of :func:`balancing`, or None
    when no block gains from one: tau from ||D E~ D||_F^2 = sum_a 4^(shift_a) B_a^2 / N_a."""
    out, shifts = [], []
    mon_shift = np.zeros(ident.n_mon, dtype=np.int64)
    for k, (size, off) in enumerate(grams):
        shift = balancing(A[k], block_exps[k][kept[k]])
        AD = congruent(A[k], shift) if shift.any() else None
        if AD is None:
            AD, shift = A[k], np.zeros_like(shift)
        out.append(AD)
        shifts.append(shift)
        i, j = svec_pairs(size)
        full = np.zeros(size, dtype=np.int64)
        full[kept[k]] = shift
        mon = ident.pair_mon[k]
        own = kept[k][i] & kept[k][j] & (owner[mon] == k)
        mon_shift[mon[own]] = full[i[own]] + full[j[own]]
    if not any(s.any() for s in shifts):
        return None
    own = owner >= 0
    scaled = np.ldexp(bound[own], mon_shift[own])
    if not np.isfinite(scaled).all():
        return None
    tau = np.sqrt(np.bincount(owner[own], weights=scaled**2 / N[own], minlength=len(grams)))
    tau = tau * (1 + float(gam(ident.n_mon + 8)))
    need = [math.nan if zero[k] < 0 else constant_need(
        AD, zero[k], float(tau[k]) * (1 + 1e-9) + 16 * (AD.shape[0] + 4) * EPS * float(np.linalg.norm(AD)))
        for k, AD in enumerate(out)]
    return out, [eig_lower(AD) for AD in out], tau, need, shifts

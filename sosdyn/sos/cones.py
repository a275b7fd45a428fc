"""Cones of Gram blocks, as rows: what ``cone=`` of every SOS-type declaration adds.

The cone of a Gram block (``cone=`` of every SOS-type declaration, :data:`CONES`), from the
smallest feasible set to the largest (Ahmadi & Majumdar 2019, "DSOS and SDSOS optimization"):

    dsos   Q_ii >= sum_{j != i} |Q_ij|                          (an LP)
    sdsos  Q = sum_{i<j} M^ij, M^ij >= 0 a 2x2 block at (i, j)   (an SOCP)
    psd    Q >= 0                                                (an SDP)

dsos is inside sdsos (a diagonally dominant Q splits into 2x2 blocks [[|Q_ij|, Q_ij],
[Q_ij, |Q_ij|]] plus a nonnegative diagonal), and sdsos inside psd (a sum of PSD blocks).

Functions on arrays: :func:`cone_rows` (with :func:`auxiliary_count`), :func:`dsos_rows` (diagonal dominance as linear rows), :func:`sdsos_rows`
(scaled diagonal dominance as linear rows and 3-dimensional second-order cones),
:func:`face_rows` (a tightened block, for rigorous bounds).
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from .constraints import LinearRows, PsdBlock
from .gram import SQRT2, svec_pairs

CONES = ("psd", "sdsos", "dsos")


def check_cone(cone, what: str = "cone") -> str:
    """``cone`` if it is one of :data:`CONES`; InputError otherwise."""
    if cone not in CONES:
        raise InputError(f"unknown {what} {cone!r}. Try: 'psd' (SOS, an SDP block), 'sdsos' "
                         "(scaled diagonally dominant, second-order cones) or 'dsos' (diagonally "
                         "dominant, an LP)")
    return cone


def auxiliary_count(psd: PsdBlock, cone: str) -> int:
    """Auxiliary decision variables ``cone`` needs for ``psd``: 0 (psd), one per off-diagonal
    svec entry (dsos: t_ij), two per off-diagonal entry (sdsos: the shares a_ij, c_ij)."""
    i, j = svec_pairs(psd.size)
    return {"psd": 0, "dsos": 1, "sdsos": 2}[check_cone(cone)] * int((i != j).sum())


def cone_rows(psd: PsdBlock, cone: str, aux: np.ndarray) -> list:
    """The rows putting ``psd`` in ``cone`` with the auxiliary ids ``aux`` (:func:`auxiliary_count`)."""
    if cone == "psd":
        return []
    if cone == "dsos":
        return [dsos_rows(psd, aux)]
    half = aux.size // 2
    return sdsos_rows(psd, aux[:half], aux[half:])


def dsos_rows(psd: PsdBlock, t: np.ndarray) -> LinearRows:
    """Q_ii >= sum_{j != i} t_ij, t_ij >= +-Q_ij (Ahmadi & Majumdar's DSOS, an LP).

    ``t`` are the ids of one auxiliary variable per off-diagonal svec entry of ``psd``.
    """
    i, j = svec_pairs(psd.size)
    off = np.flatnonzero(i != j)
    w = SQRT2 / 2                               # Q_ij = w s_k off the diagonal
    rows, ids, vals = [], [], []
    for r, k in enumerate(off):                 # t_k - w s_k >= 0 and t_k + w s_k >= 0
        rows += [2 * r, 2 * r, 2 * r + 1, 2 * r + 1]
        ids += [t[r], psd.ids[k], t[r], psd.ids[k]]
        vals += [1.0, -w, 1.0, w]
    base = 2 * off.size
    for d in range(psd.size):                   # Q_dd - sum_k t_k >= 0 over pairs touching d
        k_diag = np.flatnonzero((i == d) & (j == d))[0]
        touching = [r for r, k in enumerate(off) if i[k] == d or j[k] == d]
        rows += [base + d] * (1 + len(touching))
        ids += [psd.ids[k_diag]] + [t[r] for r in touching]
        vals += [1.0] + [-1.0] * len(touching)
    return LinearRows(f"{psd.name} (dsos)", "ge", np.array(rows, dtype=np.int64),
                      np.array(ids, dtype=np.int64), np.array(vals), np.zeros(base + psd.size), role="dsos")


def sdsos_rows(psd: PsdBlock, a: np.ndarray, c: np.ndarray) -> list:
    """Q = sum_{i<j} M^ij + D, M^ij = [[a_ij, Q_ij], [Q_ij, c_ij]] >= 0, D >= 0 diagonal (SDSOS).

    ``a``, ``c``: ids of two auxiliary variables per off-diagonal svec entry of ``psd`` (the
    share of the pair (i, j) in Q_ii and Q_jj). Rows: Q_dd - sum of the shares of d >= 0;
    and for each pair the second-order cone (a + c, 2 Q_ij, a - c), since a 2x2 matrix
    [[a, b], [b, c]] is PSD iff a + c >= ||(2b, a - c)||_2. Returns [ge rows, soc rows].
    """
    i, j = svec_pairs(psd.size)
    off = np.flatnonzero(i != j)
    r = np.arange(off.size)
    soc = LinearRows(f"{psd.name} (sdsos cones)", "soc",
                     np.concatenate([3 * r, 3 * r, 3 * r + 1, 3 * r + 2, 3 * r + 2]),
                     np.concatenate([a, c, psd.ids[off], a, c]),
                     np.concatenate([np.ones(off.size), np.ones(off.size), np.full(off.size, SQRT2),
                                     np.ones(off.size), -np.ones(off.size)]),
                     np.zeros(3 * off.size), role="sdsos")
    rows, ids, vals = [], [], []
    for d in range(psd.size):                   # Q_dd - sum of the pair shares of d >= 0
        k_diag = np.flatnonzero((i == d) & (j == d))[0]
        first = np.flatnonzero(i[off] == d)     # pairs (d, j): d's share is a
        second = np.flatnonzero(j[off] == d)    # pairs (i, d): d's share is c
        rows += [d] * (1 + first.size + second.size)
        ids += [psd.ids[k_diag]] + list(a[first]) + list(c[second])
        vals += [1.0] + [-1.0] * (first.size + second.size)
    ge = LinearRows(f"{psd.name} (sdsos)", "ge", np.array(rows, dtype=np.int64),
                    np.array(ids, dtype=np.int64), np.array(vals), np.zeros(psd.size), role="sdsos")
    return [ge, soc]


def face_rows(psd: PsdBlock, K: np.ndarray, inner: PsdBlock | None, margin) -> list:
    """Rows fixing Q = 0 outside the kept indices K and Q[K, K] = P + diag(margin) (P = ``inner``;
    ``margin`` one number or one per kept index).

    The tightened programs of proofs (``SOSProgram.tightened``) are built from them.
    """
    i, j = svec_pairs(psd.size)
    zero = np.flatnonzero(~(np.isin(i, K) & np.isin(j, K)))
    rows = [LinearRows(f"{psd.name} face", "eq", np.arange(zero.size), psd.ids[zero],
                       np.ones(zero.size), np.zeros(zero.size))]
    if inner is not None:
        a, c = svec_pairs(K.size)
        outer = K[c] * (K[c] + 1) // 2 + K[a]          # svec index of (K[a], K[c])
        k = a.size
        rows.append(LinearRows(f"{psd.name} = interior + eps I", "eq",
                               np.concatenate([np.arange(k), np.arange(k)]),
                               np.concatenate([psd.ids[outer], inner.ids]),
                               np.concatenate([np.ones(k), -np.ones(k)]),
                               np.where(a == c, np.broadcast_to(np.asarray(margin, dtype=float), (K.size,))[a], 0.0)))
    return rows

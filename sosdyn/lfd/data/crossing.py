"""Crossing demonstrations: places where a first-order autonomous system cannot follow them.

A model ``xdot = f(x)`` has one velocity per state, so two demonstration pieces that pass
through the same point with different directions cannot both be reproduced: the model's
paths never cross, and a reproduction follows one branch (or averages them) there.

* 2-D: segment intersection of the polylines (every pair of demos, and a demo with itself at
  two places more than ``2 tol`` apart along its path, so that a sharp turn is no loop).
* n-D (n >= 3): near passes, pairs of samples closer than ``tol`` (default :data:`NEAR_FRACTION`
  of the bounding-box diagonal); exact intersections in 3-D are not generic, near passes are
  what matter.

A hit counts when the two velocities point differently: more than :data:`SELF_ANGLE_DEG` apart
on one demo (a loop), more than :data:`PAIR_ANGLE_DEG` between two demos (two demos of one
motion cross at small angles as they vary; above 90 deg they disagree on the direction of
travel). Ignored: points within ``goal_radius`` (default :data:`GOAL_FRACTION` of the diagonal)
of the mean end, where every demonstration meets the others; the rest at a demo's ends, its samples
before it first leaves the ball of radius ``goal_radius`` about its first sample and after it enters
the one about its last for good (:func:`~.preprocess.rest_bounds`: an arm leaving rest wobbles back
over its start, 13 false crossings on robottasks/openbox); and samples slower than
:data:`SLOW_FRACTION` of their demo's median speed (at rest, the direction is noise).
:func:`crossing_warning` says how many, between how many demos, and the first few.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sosdyn.lfd.data.preprocess import rest_bounds

NEAR_FRACTION, GOAL_FRACTION, SLOW_FRACTION = 0.01, 0.05, 0.1
SELF_ANGLE_DEG, PAIR_ANGLE_DEG = 30.0, 90.0
MAX_POINTS = 400          # samples per demo examined (evenly subsampled above that)


@dataclass(frozen=True)
class Crossing:
    """Demos ``a`` and ``b`` (equal for a self-crossing) meet at ``point`` (data units), at
    their samples ``ia`` and ``ib``, with velocity directions ``angle_deg`` apart."""

    a: int
    b: int
    ia: int
    ib: int
    point: np.ndarray
    angle_deg: float


def _segment_hits(P: np.ndarray, Q: np.ndarray):
    """Index pairs (i, j) where segment P[i]P[i+1] properly intersects Q[j]Q[j+1] (2-D), and the
    intersection points: solve P_i + s dP_i = Q_j + u dQ_j with s, u in [0, 1)."""
    dP, dQ = np.diff(P, axis=0), np.diff(Q, axis=0)
    cross = dP[:, None, 0] * dQ[None, :, 1] - dP[:, None, 1] * dQ[None, :, 0]
    r = Q[None, :-1] - P[:-1, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (r[..., 0] * dQ[None, :, 1] - r[..., 1] * dQ[None, :, 0]) / cross
        u = (r[..., 0] * dP[:, None, 1] - r[..., 1] * dP[:, None, 0]) / cross
    i, j = np.nonzero((np.abs(cross) > 0) & (s >= 0) & (s < 1) & (u >= 0) & (u < 1))
    return i, j, P[i] + s[i, j, None] * dP[i]


def _angle(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    nv, nw = np.linalg.norm(v, axis=-1), np.linalg.norm(w, axis=-1)
    cos = np.sum(v * w, axis=-1) / np.maximum(nv * nw, np.finfo(float).tiny)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _near_passes(P, V, Q, W, tol):
    D = np.linalg.norm(P[:, None] - Q[None], axis=-1)
    i, j = np.nonzero(D < tol)
    return i, j, 0.5 * (P[i] + Q[j])


def find_crossings(demos, *, tol: float | None = None, goal_radius: float | None = None) -> list[Crossing]:
    """Every crossing of ``demos`` (module docstring), one per (demo pair, place): of the hits
    of a pair, those less than ``goal_radius`` apart are merged (the first kept)."""
    items = list(demos)
    pos = np.vstack([d.pos for d in items])
    diag = float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0))) or 1.0
    tol = NEAR_FRACTION * diag if tol is None else float(tol)
    goal_radius = GOAL_FRACTION * diag if goal_radius is None else float(goal_radius)
    goal = np.mean([d.pos[-1] for d in items], axis=0)
    keep = [np.unique(np.linspace(0, len(d.t) - 1, min(len(d.t), MAX_POINTS)).astype(int)) for d in items]
    arc = [np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(d.pos[k], axis=0), axis=1))])
           for d, k in zip(items, keep)]
    slow = [SLOW_FRACTION * np.median(np.linalg.norm(d.vel, axis=1)) for d in items]
    moving = []                                   # per demo, which kept samples are not the rest at its ends
    for d, k in zip(items, keep):
        first, last = rest_bounds(d.pos, goal_radius)
        moving.append((k > first) & (k < last))
    found = []
    for a in range(len(items)):
        for b in range(a, len(items)):
            P, V, Q, W = items[a].pos[keep[a]], items[a].vel[keep[a]], items[b].pos[keep[b]], items[b].vel[keep[b]]
            i, j, pts = (_segment_hits(P, Q) if P.shape[1] == 2 else _near_passes(P, V, Q, W, tol))
            angles = _angle(V[i], W[j])
            ok = (np.linalg.norm(pts - goal, axis=1) > goal_radius) & moving[a][i] & moving[b][j]
            ok &= angles > (SELF_ANGLE_DEG if a == b else PAIR_ANGLE_DEG)
            ok &= (np.linalg.norm(V[i], axis=1) > slow[a]) & (np.linalg.norm(W[j], axis=1) > slow[b])
            if a == b:
                ok &= (i < j) & (np.abs(arc[a][j] - arc[a][i]) > 2 * tol)
            mine = []
            for k in np.flatnonzero(ok):
                if all(np.linalg.norm(pts[k] - c.point) > goal_radius for c in mine):
                    mine.append(Crossing(a, b, int(keep[a][i[k]]), int(keep[b][j[k]]), pts[k], float(angles[k])))
            found.extend(mine)
    return found


def crossing_warning(crossings: list[Crossing], units: str = "", shown: int = 3) -> str | None:
    """A sentence for the user about ``crossings`` (None when there are none): how many, between how
    many demonstrations, and the first ``shown`` of them."""
    if not crossings:
        return None
    u = f" {units}" if units else ""
    where = "; ".join(
        (f"demo {c.a} crosses itself" if c.a == c.b else f"demos {c.a} and {c.b} cross")
        + f" at ({', '.join(f'{v:.4g}' for v in c.point)}){u}, {c.angle_deg:.0f} deg apart"
        for c in crossings[:shown])
    demos = len({d for c in crossings for d in (c.a, c.b)})
    loops = len({c.a for c in crossings if c.a == c.b})
    count = (f"{len(crossings)} crossing{'s' * (len(crossings) > 1)} involving {demos} "
             f"demonstration{'s' * (demos > 1)}" + (f" ({loops} crossing itself)" if loops else ""))
    first = f"the first {shown}: " if len(crossings) > shown else ""
    return (f"{count}; {first}{where}. A first-order model "
            "xdot = f(x) has one velocity per state and cannot follow paths that cross: expect the "
            "reproductions to take one branch or cut the loop there. Try: the second-order model, which can "
            "follow them (sosdyn fit --order 2, sosdyn.SecondOrderCDSP), demonstrations that do not cross, or "
            "split the motion at the crossing.")

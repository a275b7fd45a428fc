"""The posterior correction: a proven point one decision away from the solver's.

An interior-point solver's optimum sits on the boundary of the cone: a Gram block is singular
there, and its residual e cannot be absorbed without a margin (:mod:`.proof`). Moving one
decision t that makes every constraint it enters *more* feasible buys the margin (Loefberg
2009, *Pre- and post-processing sum-of-squares programs in practice*): changing t by s Delta
changes each constraint's polynomial by Delta h_c, h_c = s dp_c/dt, and the judge absorbs it
into the Gram block that owns its monomials as Delta H_c (the same spread as every residual,
:mod:`.proof` step 3). When every H_c is PSD -- h = 1 for "p - gamma SOS" (H = e_0 e_0^T),
y_i^2 for "P(x) - t I an SOS matrix", g(z) y_i^2 for a margin growing like g -- then

    Delta = max_c min { Delta >= 0 : lambda_min(Q~_c + Delta H_c) >= tau_c }

(the Schur complement on the constant row when h is the constant -- with several blocks
sharing it, the sum of what they lack, :func:`~.eigen.constant_need`; a bisection otherwise) is
what t must move. The moved point is then judged again by :func:`~.proof.prove_program`: this
module only proposes. Nothing here depends on how the program is written: ``maximize(g)``,
``minimize(-g)``, a cvxpy objective, extra rows, g bounding several constraints, a 1 x 1
matrix, an upper bound t + p SOS -- t moves the way the constraints say, and the objective read
at the proven point is on the safe side of the optimum because the point is feasible.
"""
from __future__ import annotations

import math

import numpy as np

from ..poly import Polynomial
from .conic import cvxpy_block_vars, positions
from .gram import svec_pairs
from .identity import EPS
from .objective import QuadraticForm, is_cvxpy
from .proof import prove_program

STEPS = 8          # judged attempts along one direction, each step a little longer


def objective_ids(program) -> np.ndarray:
    """The decision ids the objective depends on (none without an objective)."""
    sense, expr = program.objective or (None, None)
    if isinstance(expr, (Polynomial, QuadraticForm)):
        return expr.ids
    if is_cvxpy(expr):
        used = {id(v) for v in expr.variables()}
        return np.concatenate([b.ids for b, v in zip(program.blocks, cvxpy_block_vars(program)) if id(v) in used]
                              + [np.zeros(0, dtype=np.int64)])
    return np.zeros(0, dtype=np.int64)


def candidates(program) -> list:
    """Scalar decisions of the objective (``new_var()`` blocks of one id) that enter no equality row
    (nor does the program have cvxpy constraints): the decisions the correction may move. A bound
    is such a scalar; the coefficients of a free polynomial or a field are not tried."""
    if program.cvxpy_constraints:
        return []
    scalar = {int(b.ids[0]) for b in program.blocks if b.psd is None and b.ids.size == 1}
    fixed = {int(d) for rows in program.linear if rows.kind == "eq" for d in rows.ids}
    return [int(t) for t in objective_ids(program) if int(t) in scalar - fixed]


def spread(proof, h: np.ndarray) -> list:
    """The kept matrices H_k that absorb the polynomial h (by monomial of the proof's identity),
    as the judge spreads every residual: h_a / N_a on the kept pairs of the block owning x^a."""
    out = []
    ident = proof.ident
    for k, A in enumerate(proof.A):
        size = proof.kept[k].size
        i, j = svec_pairs(size)
        mon = ident.pair_mon[k]
        on = proof.kept[k][i] & proof.kept[k][j] & (proof.owner[mon] == k)
        H = np.zeros((size, size))
        H[i[on], j[on]] = h[mon[on]] / proof.N[mon[on]]
        H[j[on], i[on]] = H[i[on], j[on]]
        H = H[np.ix_(proof.kept[k], proof.kept[k])]
        out.append(H if proof.shift is None else np.ldexp(H, proof.shift[k][:, None] + proof.shift[k][None, :]))
    return out


def derivative(proof, t: int) -> np.ndarray:
    """dp/dt by monomial: the source's terms in decision t."""
    ident = proof.ident
    on = (ident.kind == 1) & (ident.where == t)
    return np.bincount(ident.mon[on], weights=ident.c1[on] * ident.c2[on], minlength=ident.n_mon)


def step_needed(proof, h) -> float:
    """The smallest Delta >= 0 with every block of ``proof`` proven after adding Delta h (module
    docstring), from floating-point eigenvalues (the judge confirms); inf if none helps."""
    if proof.ok:
        return 0.0
    if proof.owner is None:
        return math.inf
    on = np.flatnonzero(h)
    if on.size == 1 and h[on[0]] > 0 and _is_constant(proof, on[0]):
        shared = [k for k in range(len(proof.A)) if proof.zero[k] >= 0]
        if any(proof.lam[k] < proof.tau[k] for k in range(len(proof.A)) if k not in shared):
            return math.inf
        total = sum(proof.need[k] for k in shared)
        return total / float(h[on[0]]) if np.isfinite(total) and total > 0 else math.inf
    Hs = spread(proof, h)
    if any(np.linalg.eigvalsh(H)[0] < -1e-12 * max(1.0, float(np.abs(H).max())) for H in Hs if H.size):
        return math.inf

    def ok(delta):
        return all(np.linalg.eigvalsh(A + delta * H)[0] >= tau for A, H, tau in zip(proof.A, Hs, proof.tau) if A.size)
    hi = 1e-12 * max(1.0, max(float(np.abs(A).max(initial=0.0)) for A in proof.A))
    for _ in range(120):
        if ok(hi):
            break
        hi *= 4.0
    else:
        return math.inf
    lo = 0.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def _is_constant(proof, a) -> bool:
    """Monomial a of the proof's identity is the constant 1 (the square of a block's constant row)."""
    for k in range(len(proof.A)):
        if proof.zero[k] >= 0:
            i, j = svec_pairs(proof.kept[k].size)
            z = int(np.flatnonzero(proof.kept[k])[proof.zero[k]])
            return int(proof.ident.pair_mon[k][z * (z + 1) // 2 + z]) == int(a)
    return False


def moved_point(program, ids, x, judged, t: int):
    """(position of t, the sign of its move, the step) every constraint needs, or None when t cannot
    help: a failing constraint without t, or one whose H_c is not PSD."""
    step, sign = 0.0, 0.0
    for con in program.sos_constraints:
        proof = judged.constraints[con.name]
        if t not in set(con.source.ids.tolist()):
            if not proof.ok:
                return None
            continue
        if proof.ident is None:
            return None
        h = derivative(proof, t)
        on = np.flatnonzero(h)
        if not on.size:                     # t cancels in this identity: it must hold already
            if not proof.ok:
                return None
            continue
        s = 1.0 if h[on[0]] > 0 else -1.0
        if sign and s != sign:
            return None
        sign = s
        need = step_needed(proof, s * h)
        if not np.isfinite(need):
            return None
        step = max(step, need)
    if not sign or step == 0.0:
        return None
    pos = int(positions(ids, np.array([t], dtype=np.int64))[0])
    return pos, sign, step


def posterior_point(program, ids, x, judged):
    """The judge's proof (:class:`~.proof.PointProof`, its point ``x``) at a point reached by moving
    one decision (module docstring), or None."""
    for t in candidates(program):
        found = moved_point(program, ids, x, judged, t)
        if found is None:
            continue
        pos, sign, step = found
        for k in range(STEPS):
            y = x.copy()
            grow = step * (1 + 1e-9 * 10.0**k) + 4.0**k * EPS * (abs(x[pos]) + step)
            y[pos] = x[pos] + sign * grow
            at_y = prove_program(program, ids, y)
            if at_y.ok:
                return at_y
    return None

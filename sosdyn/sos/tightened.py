"""A proven point where the solver's has none: a re-solve held above the boundary, then back.

Where no single decision buys the margin (:mod:`.posterior`) -- the objective is a matrix, the
program has no objective, a free polynomial's coefficients are what must move -- the program is
solved again with every kept Gram block held above zero, Q[K, K] = P + eps D with D the
solver's diagonal (each row its own scale, eps = MARGINS) and the rows off the face fixed to
zero (``SOSProgram.tightened``). A point y_s of that program has a margin the residual fits
under, so it is proven (:func:`~.proof.prove_program`); and since the feasible set is convex,
every y(theta) = (1 - theta) y* + theta y_s with theta in [0, 1] is feasible in exact arithmetic
wherever y* is, so the smallest theta the judge proves -- directly, or after the posterior
correction (:mod:`.posterior`) has bought the constant row's margin: the re-solve then only has
to lift the directions the correction cannot reach -- found by a search in 2^-k and a bisection,
gives a proven point as close to the solver's optimum as the rounding allows; the objective
read there is on the safe side of the optimum because the point is feasible. Clarabel solves the
tightened program; when it fails or panics, SCS does (through cvxpy).
"""
from __future__ import annotations

import numpy as np

from ..errors import ResourceLimitError
from .gram import svec_pairs, svec_to_matrix
from .posterior import posterior_point
from .identity import entry_vector, identity_of, term_values
from .proof import prove_program
from .rigorous import ANSWERED

MARGINS = (1e-12, 1e-10, 1e-8, 1e-6)      # Q[K, K] >= eps diag(Q*) on each kept row (:func:`margins`), in order
RESIDUAL = 0.0                    # ... and at least this x the identity's largest residual at the solver's point
FLOOR = 1e-3                      # a Gram row's margin is at least this x the block's largest (constant row aside)
CLARABEL = dict(retry=False, prove=False, tol_feas=1e-10, tol_gap_abs=1e-10, tol_gap_rel=1e-10)
SCS = dict(solver="SCS", backend="cvxpy", retry=False, prove=False, eps=1e-8, max_iters=10_000)


def kept_rows(program, judged) -> tuple[dict, dict]:
    """(id(PsdBlock) -> the kept rows of every Gram block, constraint name -> its kept masks), from
    the faces the judge settled on."""
    rows, masks = {}, {}
    for con in program.sos_constraints:
        proof = judged.constraints.get(con.name)
        if proof is None or not proof.kept:
            continue
        masks[con.name] = [m.copy() for m in proof.kept]
        for (_, psd), mask in zip(con.gram_blocks, proof.kept):
            rows[id(psd)] = np.flatnonzero(mask)
    return rows, masks


def identity_sizes(con, at) -> tuple[list, float]:
    """(per Gram block of ``con``, the size of its identity at each row's square z_j^2 -- the sum of
    |terms| of (*) (:mod:`.proof`) on that monomial at the point, what a residual there scales
    with --, the largest |residual| of the identity there)."""
    ident = identity_of(con)
    values = term_values(ident, at, entry_vector(ident, at))
    mag = np.bincount(ident.mon, weights=np.abs(values), minlength=ident.n_mon)
    e = np.bincount(ident.mon, weights=values, minlength=ident.n_mon)
    out = []
    for k, (_, psd) in enumerate(con.gram_blocks):
        i, j = svec_pairs(psd.size)
        out.append(mag[ident.pair_mon[k][i == j]])
    return out, float(np.abs(e).max(initial=0.0))


def margins(solution, kept: dict, rel: float) -> dict:
    """id(PsdBlock) -> eps on its kept rows: for a constraint's Gram block rel x max(the solver's
    diagonal, the size of the identity at the row's square, :func:`square_magnitudes`) -- the
    residual a row must absorb scales with it, and a block the solver left near zero still needs
    it -- and at least FLOOR x the largest of these off the constant row, as the residual spreads
    over the rows, and at least RESIDUAL x the largest residual of the identity at the solver's
    point, which the re-solve's will be like; for a multiplier rel x its diagonal; for a new_sos/new_psd block rel x max(its diagonal,
    1e-3 of its largest and of 1)."""
    at = solution.values_of
    own, constants, residuals = {}, {}, {}
    for con in solution.program.sos_constraints:
        sizes, worst = identity_sizes(con, at)
        for (basis, psd), sq in zip(con.gram_blocks, sizes):
            own[id(psd)], residuals[id(psd)] = sq, worst
            constants[id(psd)] = np.flatnonzero(~basis.exps.any(axis=1))
    multipliers = {id(m.psd) for con in solution.program.sos_constraints for m in con.multipliers
                   if m.psd.role != "clique"}
    out = {}
    for b in solution.program.blocks:
        if b.psd is None or b.psd.cone != "psd" or not b.psd.size:
            continue
        d = np.abs(np.diag(svec_to_matrix(at(b.ids), b.psd.size)))
        K = kept.get(id(b.psd), np.arange(b.psd.size))
        if id(b.psd) in own:
            scale = np.maximum(d, own[id(b.psd)])
            rest = np.delete(scale, constants.get(id(b.psd), []))
            scale = np.maximum(scale, FLOOR * float(rest.max(initial=0.0)))
            out[id(b.psd)] = np.maximum(rel * scale[K], RESIDUAL * residuals[id(b.psd)])
            continue
        elif id(b.psd) in multipliers:
            scale = d
        else:
            scale = np.maximum(d, 1e-3 * max(1.0, float(d.max(initial=0.0))))
        out[id(b.psd)] = rel * scale[K]
    return out


def tightened_solve(solution, kept, rel, scs=True):
    """(the tightened program's solution, whether SCS gave it): Clarabel, then SCS when Clarabel
    fails; "infeasible" when Clarabel proves it so; None if neither answers (or the memory guard
    refuses the tightened program)."""
    try:
        tight = solution.program.tightened(kept, margins(solution, kept, rel))
        for by_scs, how in ((False, CLARABEL), (True, SCS))[:2 if scs else 1]:
            sol = tight.solve(**how)
            if sol.status in ANSWERED and np.isfinite(sol.x).all():
                return sol, by_scs
            if sol.status == "infeasible":        # a proof of it, not a numerical failure: no SCS
                return "infeasible"
    except ResourceLimitError:
        pass
    return None


def interpolate(program, ids, x, at_y, snap, prefer=None):
    """(theta, the judge's proof there) for the smallest theta found in (0, 1] with
    snap((1 - theta) x + theta y) proven, directly or after the posterior correction (``at_y``: the
    proof at y)."""
    y = at_y.x

    def proven(theta):
        point = snap((1 - theta) * x + theta * y)
        judged = prove_program(program, ids, point, prefer)
        return judged if judged.ok else posterior_point(program, ids, point, judged)
    fail, ok, best = 0.0, 1.0, at_y
    for k in (30, 24, 18, 12, 8, 4, 2, 1):
        point = proven(2.0 ** -k)
        if point is not None:
            ok, best = 2.0 ** -k, point
            break
        fail = 2.0 ** -k
    for _ in range(10):
        mid = 0.5 * (fail + ok)
        point = proven(mid)
        if point is not None:
            ok, best = mid, point
        else:
            fail = mid
    return ok, best


def tightened_point(solution, judged, snap):
    """(the judge's proof at a proven point, how it was found, notes) from a tightened re-solve
    (module docstring), else (None, "", what was tried)."""
    program, ids = solution.program, solution.data.ids
    kept, prefer = kept_rows(program, judged)
    notes, scs = [], True
    for rel in MARGINS:
        found = tightened_solve(solution, kept, rel, scs)
        if found == "infeasible":                 # every larger margin is infeasible too
            notes.append(f"held above zero ({rel:.0e}): infeasible (no interior on this face)")
            break
        if found is None:
            notes.append(f"held above zero ({rel:.0e}): no answer from Clarabel or SCS")
            continue
        sol, by_scs = found
        scs = scs and not by_scs                  # SCS, slow, is tried once
        ys = snap(sol.values_of(ids))
        at_ys = prove_program(program, ids, ys, prefer)
        if not at_ys.ok:
            moved = posterior_point(program, ids, ys, at_ys)
            if moved is None:
                notes.append(f"held above zero ({rel:.0e}{', SCS' if by_scs else ''}): {at_ys.summary()}")
                continue
            at_ys = moved
        theta, y = interpolate(program, ids, solution.x, at_ys, snap, prefer)
        return y, (f"held above zero ({rel:.0e}{', by SCS' if by_scs else ''}), then back towards the "
                   f"solver's point (theta = {theta:.2g})"), notes
    return None, "", notes

"""The point every number of a Solution is read at: one where every constraint is proven.

The solver's point y* is an approximation; what leaves sosdyn is read at a point y the judge
(:func:`~.proof.prove_program`) proves, found by these remedies in order (docs/sos-semantics.md):

1. **as solved**: y* itself, on the faces the judge tries (facial reduction first);
2. **posterior correction**: one decision of the objective moved until every constraint it
   enters has the margin its residual needs (:mod:`.posterior`);
3. **exact on the kernel's face** (programs of at most EXACT_MAX Gram entries): a rational
   certificate on the face the solver's kernel names (:mod:`.kernel`: facial reduction, an exact
   correction, exact PSD tests; Peyrl & Parrilo 2008) -- where a Gram block has no interior at
   all (Beale's function, v v^T + I), before any re-solve: cheaper, and exact (Beale's bound 0);
4. **held above zero**: a re-solve with every kept Gram block >= eps diag(Q*) -- Clarabel, then
   SCS when Clarabel fails or panics -- and back towards y* as far as the judge allows
   (:mod:`.tightened`);
5. **exact on coordinate faces** with short re-solves (:func:`~.rigorous.prove_bound`; small
   programs).

An exact certificate's numbers are the nearest floats of its rational point, its objective the
exact one rounded to the safe side.

If none succeeds, nothing is handed out: UnverifiedSolutionError says what each step found.
Before each judgement the point is projected onto the program's ``add_eq`` rows (a
least-squares step in floating point, :func:`snap`), which every remedy's point may miss by
the solver's tolerance.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from itertools import product

import numpy as np

from ..errors import ResourceLimitError, UnverifiedSolutionError
from .conic import objective_value, positions
from .kernel import KERNEL_TOLS, ROUNDINGS, kernel_bound
from .posterior import posterior_point
from .proof import certificate_point, prove_program
from .rigorous import QUICK_TIGHTENINGS, Bound, confirm, prove_bound
from .tightened import tightened_point

_UNVERIFIED_HINTS = {
    "SCS": "solver='CLARABEL' (the default interior-point solver, far more accurate than SCS), "
           "or tighter SCS tolerances (eps=1e-9, max_iters=100000)",
    None: "tighter solver tolerances (Clarabel: tol_feas=1e-10, tol_gap_abs=1e-10, "
          "tol_gap_rel=1e-10), rescale the problem data, or give the program more margin "
          "(a small positive margin in strict inequalities, a lower degree)",
}
EXACT_MAX = 10_000      # Gram entries up to which the exact certificate is tried (rational arithmetic
#                         on Broyden n = 1000, 54,890 entries, ran over 15 minutes)


def unverified_hint(solver: str) -> str:
    """What to try when a solver's answer fails the independent check."""
    return _UNVERIFIED_HINTS.get(solver, _UNVERIFIED_HINTS[None])


@dataclass
class Proof:
    """Where a Solution's numbers are read: ``x`` (ordered as the solution's ``data.ids``), how it
    was found (``method``), what the earlier remedies found (``tried``); ``exact`` is the
    :class:`~.rigorous.Bound` when the exact certificate gave it, ``judged`` the floating-point
    proof at x (from which :func:`certified` reads the Gram matrices to hand out)."""

    x: np.ndarray
    method: str
    tried: list = field(default_factory=list)
    exact: object = None
    judged: object = None          # the judge's verdict at x (its certificates: :func:`certified`)


def snap(program, ids):
    """x -> x projected onto the program's ``add_eq`` rows (least squares over the decisions they
    touch; x itself when there are none or they hold already)."""
    rows = [r for r in program.linear if r.role == "user" and r.kind == "eq"]
    if not rows:
        return lambda x: x
    cols = np.unique(np.concatenate([r.ids for r in rows]))
    pos = positions(ids, cols)
    n_rows = sum(r.rhs.size for r in rows)
    A = np.zeros((n_rows, cols.size))
    b = np.concatenate([r.rhs for r in rows])
    start = 0
    for r in rows:
        np.add.at(A, (start + r.rows, np.searchsorted(cols, r.ids)), r.vals)
        start += r.rhs.size
    pinv = np.linalg.pinv(A)

    def project(x):
        y = x.copy()
        for _ in range(2):
            resid = A @ y[pos] - b
            if not np.any(resid):
                break
            y[pos] = y[pos] - pinv @ resid
        return y
    return project


@dataclass
class Pending:
    """What the remedies without a re-solve found (:func:`cheap_proof`): the judged point, the
    judge's verdict there and what was tried; the re-solving remedies continue from it."""

    x: np.ndarray
    judged: object
    tried: list


def certified(program, ids, proof: Proof) -> np.ndarray:
    """The proven point with its blocks replaced by the certificates proven there
    (:func:`~.proof.certificate_point`: PSD multipliers, the absorbed Gram matrices), when that
    point is proven too (it is, up to rounding), else the point itself."""
    if proof.judged is None:
        return proof.x
    z = certificate_point(program, ids, proof.x, proof.judged)
    return z if prove_program(program, ids, z).ok else proof.x


def cheap_proof(solution):
    """Remedies 1 and 2 of the module docstring (no re-solve: ``SOSProgram.solve`` runs them at
    once, while the program is the one solved): a :class:`Proof`, or the :class:`Pending` state."""
    program, ids = solution.program, solution.data.ids
    x = snap(program, ids)(solution.x)
    judged = prove_program(program, ids, x)
    if judged.ok:
        return Proof(judged.x, "as solved", judged=judged)
    tried = [f"as solved: {judged.summary()}"]
    moved = posterior_point(program, ids, x, judged)
    if moved is not None:
        return Proof(moved.x, "posterior correction", tried, judged=moved)
    tried.append("posterior correction: no decision of the objective makes every failing constraint "
                 "more feasible by a sum of squares" if program.objective else
                 "posterior correction: no objective to move")
    return Pending(x, judged, tried)


def full_proof(solution, pending: Pending) -> Proof:
    """Remedies 3 to 5 after :func:`cheap_proof` found none; UnverifiedSolutionError naming what
    each remedy found when none gives a proven point."""
    program, tried = solution.program, list(pending.tried)
    entries = sum(b.psd.size * (b.psd.size + 1) // 2 for b in program.blocks if b.psd is not None)
    small = entries <= EXACT_MAX
    if small:
        for keep in (False, True):
            why, found, skip = [], [], set()
            for rounding, tol, squares in product(ROUNDINGS, KERNEL_TOLS, (False, True)):
                if rounding in skip:
                    continue
                try:
                    found.append(kernel_bound(program, solution.data, solution.x, keep, tol, squares, rounding))
                except UnverifiedSolutionError as exc:
                    why.append(f"{tol:.0e}{', zero squares' if squares else ''}, denominators <= {rounding[0]}: "
                               f"{exc.detail}")
                    if "coefficient equations," in exc.detail or "exact form" in exc.detail:
                        break                                       # the same at any tolerance and rounding
                    if "inconsistent" in exc.detail:
                        skip.add(rounding)                          # read so, the kernel is not the face's
                if found and min(found[-1].margins.values(), default=1.0) > 0:
                    break                         # a face with a margin: the one to report
            if found:
                bound = max(found, key=lambda b: min(b.margins.values(), default=1.0))
                return Proof(bound.x, "exact on the face of the solver's kernel", tried, bound)
            tried.append(f"exact on the kernel's face{' (constant kept)' if keep else ''}: {'; '.join(why)}")
            if "exact form" in why[-1]:
                break
    y, how, notes = tightened_point(solution, pending.judged, snap(program, solution.data.ids))
    tried += notes
    if y is not None:
        return Proof(y.x, how, tried, judged=y)
    if small:
        try:
            bound = prove_bound(program, solution.data, solution.x, QUICK_TIGHTENINGS)
            return Proof(bound.x, f"exact ({bound.method})", tried, bound)
        except (UnverifiedSolutionError, ResourceLimitError) as exc:
            tried.append(f"exact on coordinate faces: {getattr(exc, 'detail', exc)}")
    else:
        tried.append(f"exact certificates: not tried ({entries} Gram entries, above {EXACT_MAX})")
    raise UnverifiedSolutionError(
        f"no point near the {solution.solver} answer to {program.name!r} could be proven, so no number "
        f"from it is returned. Tried: {' | '.join(tried)}", "unverified",
        "rescale the variables so the solution lies near the unit box, a lower degree, give the program "
        "some margin (a strict inequality held by a small positive amount), or prog.solve(rigorous=True)")


def exact_bound(solution) -> Bound:
    """The bound of rigorous mode: the best of the exact certificates at hand -- the proof's own
    when it is exact, :func:`~.rigorous.confirm` at the float-proven point (on the judge's faces),
    and :func:`~.rigorous.prove_bound`'s search from the solver's point; UnverifiedSolutionError
    when none proves it."""
    program, data = solution.program, solution.data
    found, errors = [], []
    try:
        proof = solution.proof
    except UnverifiedSolutionError:
        proof = None
    if proof is not None and proof.exact is not None:
        found.append(replace(proof.exact, solver_value=objective_value(data, solution.x) if proof.exact.sense else None))
    elif proof is not None:
        judged = prove_program(program, data.ids, proof.x)
        kept = {id(psd): np.flatnonzero(mask) for con in program.sos_constraints if judged.constraints[con.name].kept
                for (_, psd), mask in zip(con.gram_blocks, judged.constraints[con.name].kept)}
        confirmed = confirm(program, data, proof.x, kept, solution.x)
        if confirmed is not None:
            found.append(confirmed)
    if not found or found[0].sense is not None:
        try:
            found.append(prove_bound(program, data, solution.x, solver_x=solution.x))
        except UnverifiedSolutionError as exc:
            errors.append(exc)
    if not found:
        raise errors[0]
    best = max if found[0].sense == "max" else min
    return best(found, key=lambda b: b.proven) if found[0].sense else found[0]


def refusal(solution, pending: Pending) -> UnverifiedSolutionError:
    """The error of an answer that fails the check and whose point the cheap remedies cannot prove."""
    return UnverifiedSolutionError(
        f"the {solution.solver} answer to {solution.program.name!r} fails the independent check, and no "
        f"point near it could be proven, so no number from it is returned: {solution.verify().summary()}. "
        f"Tried: {' | '.join(pending.tried)}", "unverified", unverified_hint(solution.solver), solution.verify())

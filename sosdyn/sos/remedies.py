"""What ``SOSProgram.solve`` does when the solver's first answer is not one sosdyn can return.

* **Numerical trouble** -- a solver error (Clarabel's ``NumericalError``,
  ``InsufficientProgress``, ...) or an answer that fails the independent check (typically
  ``optimal_inaccurate`` on a program without an interior: a Gram block whose smallest
  eigenvalue is -3e-6 where the check allows -2.8e-6). The same program is solved again with
  the remedies of :data:`REMEDIES`, in order, until one answer passes the whole check; each
  changes only how the solver works, never the program, so a passing answer is an answer to
  the program as stated. Measured on chained singular (n = 16..36, correlative) and Broyden
  tridiagonal (n = 6, correlative): flipping the row scaling, a 10x larger static
  regularisation, or tighter iterative refinement each turns the refusal into a verified
  answer (and a combination of them, or tighter tolerances, where one alone does not). Not
  every refusal goes away: chained singular n = 40 and 60 stay refused after all of them
  (block eigenvalues -3e-6 ... -1.7e-5 against -2.8e-6; its Gram blocks have no interior: with
  every block >= 1e-7 I relative it is primal infeasible; capping the objective short of the
  first answer does not help either, measured).
* **Unbounded** -- a solver that reports dual infeasibility (no finite optimum) may be wrong
  about it (maximize g with p - g SOS and the row g <= 1e12: Clarabel said "DualInfeasible" on
  the scaled rows, measured), so the remedies above are tried too and an answer that passes the
  check is taken; still "unbounded", it is solved once more without the user's inequalities
  whose constant is far above their coefficients (:func:`far_rows`), and an answer that passes
  the check -- which reads those rows -- is the program's. Nor has it shown that the constraints can be met: with an infeasible SOS
  constraint and an objective variable that no constraint mentions, Clarabel says "unbounded".
  The program is then solved once more without its objective (:func:`feasibility_status`); if
  that is infeasible, the status is "infeasible" with that reason.
* **A free variable of odd degree** -- ``p >= 0 on K`` where p has odd degree in a variable
  no constraint of K mentions (min over K = -inf) has no certificate; a solver may say so or
  stop with a numerical error. After such a failure the status is "infeasible" with that
  cause (:func:`free_odd_variable`), as the sparse path says of a monomial no block produces.

Every attempt, the first included, is recorded in ``sol.info["attempts"]`` (settings, scale,
status, whether it passed, why not) and its time in ``sol.timings["retries"]``.
"""
from __future__ import annotations

import copy
import time

import numpy as np

from .backends import solve_program
from .rigorous import ANSWERED
from .solution import Solution

FAR = 1e6

#: (name, "flip" or "keep" the row scaling, Clarabel settings), tried in order
REMEDIES = (
    ("row scaling flipped", "flip", {}),
    ("static regularisation 1e-7", "keep", {"static_regularization_constant": 1e-7}),
    ("iterative refinement to 1e-14", "keep", {"iterative_refinement_reltol": 1e-14,
                                                "iterative_refinement_abstol": 1e-14,
                                                "iterative_refinement_max_iter": 50}),
    ("row scaling flipped, static regularisation 1e-7", "flip", {"static_regularization_constant": 1e-7}),
    ("tolerances 1e-10, 400 iterations", "keep", {"tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10,
                                                  "tol_feas": 1e-10, "max_iter": 400}),
)


def acceptable(sol) -> bool:
    """The answer is one sosdyn returns: answered and the whole certificate passes."""
    return sol.status in ANSWERED and sol.verify().passed


def _record(name, scale, settings, sol, seconds) -> dict:
    passed = acceptable(sol)
    why = "" if passed else (sol.verify().summary() if sol.status in ANSWERED else sol.raw_status)
    return {"remedy": name, "scale": scale, "settings": dict(settings), "status": sol.status,
            "raw_status": sol.raw_status, "passed": passed, "reason": why[:300], "seconds": seconds}


def needs_remedy(sol) -> bool:
    """A solver error, an answer that fails the check, or "unbounded" (a report that large numbers in a
    row -- x <= 1e12 -- can provoke: another scaling may find the finite optimum). Not "infeasible":
    decided."""
    return sol.status in ("solver_error", "unbounded") or (sol.status in ANSWERED and not sol.verify().passed)


def free_odd_variable(con) -> str | None:
    """Why "con.source >= 0 on K" has no certificate, if a variable v that no constraint of K
    mentions has odd top degree in the source, with fixed (numeric) coefficients there.

    Then at any point of K where the top coefficient c(x) of v is non-zero, the source is
    unbounded below in v, while every sigma_0 + sum sigma_i g_i is >= 0 there for all v (the
    g_i do not depend on v): no certificate exists, whatever the multipliers' degree (unless
    c vanishes on all of K). None if there is no such variable."""
    p = con.source
    on_set = {v for m in con.multipliers + con.eq_multipliers for v in m.constraint.vars
              if m.constraint.exps[:, m.constraint.vars.index(v)].any()}
    fixed = ~p.coef[:, 1:].any(axis=1) & (p.coef[:, 0] != 0)
    for c, v in enumerate(p.vars):
        deg = p.exps[:, c]
        if v in on_set or not deg.any():
            continue
        top = deg == deg.max()
        if deg.max() % 2 and fixed[top].all():
            return (f"constraint {con.name!r}: the polynomial has odd degree {int(deg.max())} in {v}, which no "
                    f"constraint of the set mentions, so it is unbounded below in {v} on the set (min = -inf "
                    f"wherever its coefficient of {v}^{int(deg.max())} is non-zero): no certificate exists; "
                    f"bound {v} in the set (e.g. 1 - {v}^2 >= 0 after rescaling) or leave it out of the polynomial")
    return None


def far_rows(program) -> list:
    """The user's inequality rows whose constant is above FAR times their largest coefficient (x <=
    1e12): a solver may call the program unbounded because of them; solved without them, an answer
    that satisfies them (the check reads every row of the program) is the program's."""
    out = []
    for rows in program.linear:
        if rows.role == "user" and rows.kind == "ge" and rows.rhs.size:
            size = np.zeros(rows.rhs.size)
            np.maximum.at(size, rows.rows, np.abs(rows.vals))
            if (np.abs(rows.rhs) > FAR * np.maximum(size, 1e-300)).all():
                out.append(rows)
    return out


def feasibility_status(program, solver, backend, scale, settings) -> str:
    """The solver's status for ``program``'s constraints alone (its objective dropped)."""
    bare = copy.copy(program)
    bare.objective, bare._compiled = None, None
    return solve_program(bare, solver=solver, backend=backend, scale=scale, verbose=False, **settings).status


def solve_with_remedies(program, solver, backend, scale, verbose, build, settings, retry=True):
    """:func:`.backends.solve_program`, then the remedies of the module docstring when needed."""
    t0 = time.perf_counter()
    first = solve_program(program, solver=solver, backend=backend, scale=scale, verbose=verbose,
                          build=build, **settings)
    attempts = [_record("as asked", scale, settings, first, time.perf_counter() - t0)]
    chosen, chosen_at = first, 0
    direct = first.backend == "direct"
    if first.status in ("solver_error", "infeasible", "unbounded"):
        why = next(filter(None, (free_odd_variable(c) for c in program.sos_constraints if c.kind == "nonneg_on")), None)
        if why:
            first.status, first.reason, retry = "infeasible", why, False
    if retry and needs_remedy(first):
        for name, how, extra in REMEDIES:
            if (extra and not direct) or set(extra) & set(settings):
                continue                      # Clarabel's own settings; never override the user's
            t1 = time.perf_counter()
            s = (not scale) if how == "flip" else scale
            sol = solve_program(program, solver=solver, backend=backend, scale=s, verbose=verbose,
                                build=build, **{**settings, **extra})
            attempts.append(_record(name, s, {**settings, **extra}, sol, time.perf_counter() - t1))
            if acceptable(sol):
                chosen, chosen_at = sol, len(attempts) - 1
                break
    far = far_rows(program) if retry and chosen.status == "unbounded" and program.objective is not None else []
    if far:
        t1 = time.perf_counter()
        relaxed = copy.copy(program)
        relaxed.linear, relaxed._compiled = [r for r in program.linear if not any(r is q for q in far)], None
        sol = solve_program(relaxed, solver=solver, backend=backend, scale=scale, verbose=verbose, build=build,
                            **settings)
        sol = Solution(program, program.compile(scale=scale), sol.status, sol.x, sol.solver, sol.backend,
                       sol.timings, sol.raw_status, sol.info)
        attempts.append(_record(f"without the far inequalities {[r.name for r in far]}", scale, settings, sol,
                                time.perf_counter() - t1))
        if acceptable(sol):
            chosen, chosen_at = sol, len(attempts) - 1
    if retry and chosen.status == "unbounded" and program.objective is not None:
        t1 = time.perf_counter()
        status = feasibility_status(program, solver, backend, scale, settings)
        attempts.append({"remedy": "constraints alone (objective dropped)", "scale": scale,
                         "settings": dict(settings), "status": status, "raw_status": status,
                         "passed": status != "infeasible", "reason": "", "seconds": time.perf_counter() - t1})
        if status == "infeasible":
            first.status = "infeasible"
            first.reason = ("the solver reported the objective unbounded, but the constraints alone are "
                            "infeasible: no point satisfies them, so there is nothing to optimise")
    chosen.info["attempts"] = attempts
    chosen.timings["retries"] = sum(a["seconds"] for k, a in enumerate(attempts) if k != chosen_at)
    return chosen

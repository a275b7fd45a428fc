"""Lower bounds of a polynomial on a basic semialgebraic set (the Lasserre/Putinar hierarchy).

    f* = min_{x in K} f(x)  >=  gamma* = max { gamma : f - gamma >= 0 on K, certified }

with the certificate of :meth:`SOSProgram.add_nonneg_on` (Putinar multipliers up to
``degree``, optionally the preorder's products; :mod:`.sets`) or, for K = R^n, f - gamma SOS.
The relaxation's value gamma* is nondecreasing in the degree and converges to f* when K is
compact with an Archimedean description (Lasserre 2001). The *returned* bound is the objective
at a proven point (:mod:`.proven`): <= gamma* <= f*, but not always nondecreasing in the degree
-- a higher degree's certificate can be harder to prove near its optimum (measured: x y on the
box [-50, 80]^2, exact -4000: -4112.5 at degree 2; rescaled, -4000.000 at degree 4). Before any
solve and at every degree:

* **no finite bound**: a ray x0 + s r inside K along which f -> -inf, proven in rational
  arithmetic (:func:`~.sets.unbounded_ray`), is an InfeasibleError (no gamma is a bound);
* **rescaled**: when K bounds every variable in a box [lo, hi] far from the unit box, the
  program is solved for f(c + w u) on the pulled-back set (c the box's centre, w its half-widths;
  :func:`~.sets.substituted`: exact coefficients rounded, the rounding subtracted from f and
  added to every g_i, so the bound stays a bound of the original problem); ``LowerBound.minimizers``
  maps the points back;
* **balanced**: otherwise, when the coefficients of f and of K's polynomials span many orders of
  magnitude that a change of variables x = 2^k u evens out (:func:`balancing`: least squares on
  log2 |c_a| + a . k, each polynomial its own level; taken when it narrows f's spread by
  BALANCE_GAIN bits), the program is solved for f(2^k u) on the pulled-back set -- the same
  problem, its coefficients scaled exactly by powers of two ((100 x - 1)^2 + (y/100 - 2)^2 +
  (x y - 2)^2 + 3 becomes one with coefficients 0.6 ... 12, which SCS solves too);
* **centred**: a global bound (K = R^n) that lost more than GAP (relative) to the solver's value
  is computed again for f(c + u), c the minimiser the moment matrix gives (:func:`recentred`);
* **refined**: a bound that lost more than GAP (relative) to the solver's value in floating point
  (not an exact certificate: its value is the exact system's) is solved again under each of the
  solver settings of :data:`~.remedies.REMEDIES` in turn (:func:`sharpening` first), until one's
  bound is within GAP of its solver's value; the best proven bound is kept (:func:`refined`).
  Each is the objective at a proven point of the same program, so the best is a bound. What
  loses the margin is the solver's last iterate: where its Gram block is indefinite off the
  constant row (T_7(t - 2) on [1, 3]: lambda_min -1.5e-8; Broyden tridiagonal n = 10: -6e-9),
  no move of gamma repairs it, and the re-solve held above zero, then back, lost up to 1.7e-5 on
  some OpenBLAS kernels; with tighter iterative refinement (or tolerances) the iterate is one the
  correction proves;
* **lower degree**: when no point of the degree-d relaxation is proven (UnverifiedSolutionError,
  or a solver error), degrees d - 2, d - 4, ... are tried and the first proven bound returned
  (``LowerBound.degree`` says which): a bound valid at a lower degree is never refused at a
  higher one.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InfeasibleError, InputError, SolverError, UnverifiedSolutionError
from ..poly import Polynomial, match_rows
from .constraints import SOSConstraint, as_sos_polynomial
from .moments import Atoms
from .program import SOSProgram
from .remedies import REMEDIES
from .rigorous import ANSWERED
from .sets import BasicSet, as_set, substituted, unbounded_ray, variable_box
from .solution import Solution

GAP = 1e-6                 # a global bound this far (relative) below the solver's value is solved again, centred
UNIT_BOX = (0.25, 2.0)     # a box is left as it is when every half-width >= 0.25 and |centre| + half-width <= 2
BALANCE_GAIN = 10          # bits of f's coefficient spread a change of variables x = 2^k u must save to be made


@dataclass
class LowerBound:
    """A bound ``value`` <= min f on the set, with its program and certificate.

    ``value`` is ``solution.objective`` (the objective at the proven point, :mod:`.proven`), or with
    ``rigorous=True`` the bound proven in exact arithmetic, minus the rounding of a rescaling;
    ``solver_value`` the solver's gamma. ``degree``: the relaxation degree that gave it;
    ``center``/``half``: the rescaling x = center + half * u the program was solved in (None: none).
    """

    value: float
    solution: Solution
    constraint: SOSConstraint
    program: SOSProgram
    solver_value: float = float("nan")
    degree: int | None = None
    center: np.ndarray | None = field(default=None, repr=False)
    half: np.ndarray | None = field(default=None, repr=False)

    def minimizers(self, con=None, **kw) -> Atoms:
        """The points attaining the bound (``Solution.minimizers`` of ``con``, default the bound's
        constraint), in the problem's own variables; a multiplier or another program's constraint
        raises InputError saying what to pass."""
        atoms = self.solution.minimizers(self.constraint if con is None else con, **kw)
        if self.center is not None:
            atoms.points = self.center + self.half * atoms.points
        return atoms


def rescaling(f: Polynomial, K: BasicSet):
    """(center, half) of the box K bounds every variable of f and K in, when it is far from the unit
    box (UNIT_BOX) and K has no equalities; else None."""
    if K.eqs or not K.ineqs:
        return None
    vars = f.vars + tuple(v for v in K.vars if v not in f.vars)
    box = variable_box(K, vars)
    if box is None:
        return None
    center, half = (box[0] + box[1]) / 2, (box[1] - box[0]) / 2 * (1 + 1e-12)
    if (half <= 0).any() or ((half >= UNIT_BOX[0]).all() and (np.abs(center) + half <= UNIT_BOX[1]).all()):
        return None
    return vars, center, half


def balancing(polys, vars) -> np.ndarray | None:
    """Integer k (one per variable of ``vars``) with x = 2^k u making the coefficients of each
    polynomial most even (module docstring), or None when it saves f (the first) fewer than
    BALANCE_GAIN bits of spread or a scaled coefficient would leave the normal floats."""
    rows, logs, level = [], [], []
    for n, p in enumerate(polys):
        q = p.with_vars(vars)
        on = q.coef[:, 0] != 0
        rows.append(q.exps[on])
        logs.append(np.log2(np.abs(q.coef[on, 0])))
        level.append(np.full(int(on.sum()), n))
    E, c, lv = np.vstack(rows), np.concatenate(logs), np.concatenate(level)
    if c.size < 2:
        return None
    M = np.hstack([E.astype(float), -np.eye(len(polys))[lv]])
    k = np.rint(np.linalg.lstsq(M, -c, rcond=None)[0][:len(vars)]).astype(np.int64)
    first = lv == 0
    after = c[first] + E[first] @ k
    if np.ptp(c[first]) - np.ptp(after) < BALANCE_GAIN or np.abs(c + E @ k).max() > 1000:
        return None
    return k


def scaled_variables(p: Polynomial, vars, k) -> Polynomial:
    """p(2^k u) over ``vars``: every coefficient times a power of two, exact (:func:`balancing`
    keeps them in the normal range)."""
    q = p.with_vars(vars)
    coef = q.coef.copy()
    coef[:, 0] = np.ldexp(coef[:, 0], q.exps @ k)
    return Polynomial(vars, q.exps, coef, q.ids)


def minimize_on(f, K: BasicSet | None = None, degree=None, products=False, sparsity=None, cone="psd",
                **solve) -> LowerBound:
    """max gamma such that f - gamma >= 0 on K (module docstring); ``solve``: SOSProgram.solve's
    keywords (``rigorous=True`` for a bound proven in exact arithmetic)."""
    f = as_sos_polynomial(f)
    K = as_set(() if K is None else K)
    if not (K.ineqs or K.eqs) and (degree is not None or products):
        raise InputError("degree= and products= shape the multipliers of a set; K has no constraints. "
                         "Try: minimize_on(f) for a global bound, or pass the set K")
    ray = unbounded_ray(f, K) if f.is_numeric else None
    if ray is not None:
        raise InfeasibleError(
            f"{f!r} has no finite lower bound on the set: along x = {ray[0].tolist()} + s * {ray[1].tolist()} "
            "(over the variables of f, then of the set) every constraint holds for all s >= 0 and f -> -inf, "
            "so no gamma is a bound at any degree (proven in rational arithmetic)", "infeasible",
            "bound the variables in the set (a box or a ball), or check the sign of the objective")
    scaled = rescaling(f, K) if f.is_numeric else None
    if scaled is not None:
        vars, center, half = scaled
        f_u, f_err, _ = substituted(f.with_vars(vars), center, half)
        ineqs = []
        for g in K.ineqs:
            g_u, g_err, _ = substituted(g.with_vars(vars), center, half)
            ineqs.append(g_u + g_err)
        f, K, shift = f_u - f_err, BasicSet(ineqs), (center, half)
    else:
        shift = (None, None)
        vars = f.vars + tuple(v for v in K.vars if v not in f.vars)
        k = balancing((f,) + K.ineqs + K.eqs, vars) if f.is_numeric else None
        if k is not None:
            f, K = scaled_variables(f, vars, k), BasicSet([scaled_variables(g, vars, k) for g in K.ineqs],
                                                          [scaled_variables(h, vars, k) for h in K.eqs])
            shift = (np.zeros(len(vars)), np.ldexp(1.0, k))
    degrees = [degree]
    if K.ineqs and isinstance(degree, (int, np.integer)) and not isinstance(degree, bool):
        lowest = max([f.degree] + [g.degree for g in K.ineqs + K.eqs])
        degrees += [d for d in range(int(degree) - 2, lowest - 1, -2)]
    failures = []
    for d in degrees:
        try:
            lb = _lower_bound(f, K, d, products, sparsity, cone, shift, solve)
        except InfeasibleError:
            raise
        except (UnverifiedSolutionError, SolverError) as exc:
            failures.append(exc)
            continue
        centre = not (K.ineqs or K.eqs or solve.get("rigorous")) and f.is_numeric   # exact proofs read f(c + u)'s
        return recentred(lb, f, sparsity, cone, solve) if centre else lb              # floats: not with rigorous
    if len(failures) > 1:
        first = failures[0]
        first.args = (f"{first}\n(lower degrees {degrees[1:]} were tried too, and no bound was proven at any)",)
    raise failures[0]


def recentred(lb: LowerBound, f: Polynomial, sparsity, cone, solve) -> LowerBound:
    """The global bound again for f(c + u), c the minimiser the moments give, when the bound lost
    more than GAP (relative) to the solver's value; the better bound of the two. Centred there, the
    identity's monomials are no longer large where f is small, so the solver's answer and its
    correction are accurate. f(c + u)'s coefficients are exact rationals rounded to floats; the
    proof absorbs each rounding like a residual (``source_error``), so the bound is one of f."""
    if lb.solver_value - lb.value <= GAP * max(1.0, abs(lb.solver_value)):
        return lb
    try:
        c = lb.minimizers().points[0]
    except (SolverError, InputError):
        return lb
    if lb.center is not None:                   # lb's points were mapped back from f's variables
        c = (c - lb.center) / lb.half
    g, _, rounding = substituted(f, c, np.ones(c.size))
    outer = (lb.center, lb.half) if lb.center is not None else (np.zeros(c.size), np.ones(c.size))
    try:
        again = _lower_bound(g, BasicSet(), None, False, sparsity, cone, (outer[0] + outer[1] * c, outer[1]),
                             solve, rounding)
    except (SolverError, InputError):      # unproven there, or numbers no solver resolves: keep the first
        return lb
    return again if again.value > lb.value else lb


def _lower_bound(f, K, degree, products, sparsity, cone, shift, solve, rounding=None) -> LowerBound:
    """The bound of one relaxation; ``rounding`` (a polynomial of bounds on the roundings of f's
    coefficients) is attached to the constraint for the proof (:mod:`.proof`, ``source_error``)."""
    prog = SOSProgram("minimize_on")
    gamma = prog.new_var(name="gamma")
    if K.ineqs or K.eqs:
        con = prog.add_nonneg_on(f - gamma, K, degree=degree, products=products, sparsity=sparsity, cone=cone)
    else:
        con = prog.add_sos(f - gamma, sparsity=sparsity, cone=cone)
    if rounding is not None:
        src = con.source.with_vars(con.basis.vars)
        E = np.zeros(src.coef.shape)
        rows = match_rows(src.exps, rounding.with_vars(src.vars).exps)
        E[rows[rows >= 0], 0] = rounding.coef[rows >= 0, 0]
        con.source_error = lambda: E
    prog.maximize(gamma)
    sol = prog.solve(raise_on_failure=True, **solve)
    return refined(LowerBound(float(sol.objective), sol, con, prog, sol.solver_objective, degree, *shift), solve)


def lost(lb: LowerBound) -> bool:
    """The proven bound is more than GAP (relative) below the solver's value."""
    return lb.solver_value - lb.value > GAP * max(1.0, abs(lb.solver_value))


def sharpening(remedy) -> int:
    """Sort key of REMEDIES for :func:`refined`: the settings that only make the solve more accurate
    first -- iterative refinement (0), tighter tolerances (1) -- then the others (2). Measured, they
    closed the gap first: T_7(t - 2) on [1, 3] and Broyden n = 10 under four OpenBLAS kernels,
    Broyden n = 40 (-3.1e-6 -> -3.4e-8 in 6.8 s more; in REMEDIES' order, 35 s)."""
    settings = remedy[2]
    return 0 if "iterative_refinement_reltol" in settings else 1 if "tol_gap_abs" in settings else 2


def refined(lb: LowerBound, solve) -> LowerBound:
    """``lb``, or the best bound of its program solved again under REMEDIES' settings (module
    docstring) when it lost more than GAP in floating point; the user's own settings (and
    ``retry=False``, ``rigorous=True``) are never overridden."""
    if not lost(lb) or lb.solution.proof.exact is not None or solve.get("rigorous") or not solve.get("retry", True):
        return lb
    best, scale, direct = lb, solve.get("scale", True), lb.solution.backend == "direct"
    for _, how, extra in sorted(REMEDIES, key=sharpening):
        if (extra and not direct) or set(extra) & set(solve) or (how == "flip" and "scale" in solve):
            continue
        sol = lb.program.solve(**{**solve, **extra, "scale": (not scale) if how == "flip" else scale})
        if sol.status not in ANSWERED or not sol.verified:
            continue
        again = LowerBound(float(sol.objective), sol, lb.constraint, lb.program, sol.solver_objective, lb.degree,
                           lb.center, lb.half)
        best = again if again.value > best.value else best
        if not lost(again):
            break
    return best

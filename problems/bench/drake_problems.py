"""The SOS benchmark problems written a third time: for Drake (pydrake's ``MathematicalProgram``,
``NewIndeterminates`` / ``NewSosPolynomial`` / ``AddSosConstraint``), solved by Drake's own
Clarabel wrapper, and the runner that times them.

Each builder goes from plain numbers to a program with every constraint, as a Drake user would
write it (symbolic expressions or ``symbolic.Polynomial`` maps; Drake picks the Gram basis from
the Newton polytope, as sosdyn does). Matrix SOS constraints ``G(x) ⪰ 0`` become the scalar
``yᵀ G(x) y`` SOS in extra indeterminates ``y`` (Drake has no matrix SOS call; sosdyn's
multipartite basis y⊗z(x) is the same formulation). pydrake (``drake`` on PyPI, the bench extra)
is imported inside the builders: it is optional, and only this comparison needs it.

Timings of one run: ``build`` (wall, plain numbers to program), ``solve`` (Clarabel's own time,
``solver_details.solve_time``), ``canonicalize`` (``ClarabelSolver.Solve`` wall minus that:
Drake's translation of the program to Clarabel's conic form).
"""
from __future__ import annotations

import numpy as np

from . import sos_problems as S
from .timing import median, now

#: Problems of :func:`.catalog.problems` without a Drake version, with the reason.
NOT_WRITTEN = {"CDSP metric step (n=2, K=6, metric deg 2)":
               "built from the learner's fitted components (sosdyn data structures); not ported"}

#: Drake's SolutionResult names -> sosdyn's status words.
STATUS = {"kSolutionFound": "optimal", "kInfeasibleConstraints": "infeasible", "kUnbounded": "unbounded",
          "kInfeasibleOrUnbounded": "infeasible_or_unbounded", "kDualInfeasible": "unbounded",
          "kSolverSpecificError": "solver_error", "kIterationLimit": "solver_error"}


def available() -> str | None:
    """The pydrake version if it imports and its Clarabel wrapper is usable, else None."""
    try:
        import pydrake
        from pydrake.solvers import ClarabelSolver
    except ImportError:
        return None
    return getattr(pydrake, "__version__", "?") if ClarabelSolver().available() else None


def program(n, name="x"):
    from pydrake.solvers import MathematicalProgram
    prog = MathematicalProgram()
    return prog, prog.NewIndeterminates(n, name)


# ---------------------------------------------------------------------- builders
def feas(expr_fn, n):
    """``expr_fn(x) is SOS`` in n indeterminates."""
    def build():
        prog, xs = program(n)
        prog.AddSosConstraint(expr_fn(*xs))
        return prog
    return build


def motzkin_max_gamma():
    prog, (x, y) = program(2)
    g = prog.NewContinuousVariables(1, "g")[0]
    prog.AddSosConstraint(S.motzkin(x, y) - g)
    prog.AddLinearCost(-g)
    return prog


def chebyshev(degree=8):
    """max lead coefficient of p, 1 ∓ p − s±·(1 − x²) SOS, s± SOS of degree ``degree − 2``."""
    from pydrake.symbolic import Monomial, Variables
    prog, (x,) = program(1)
    X = Variables([x])
    p = prog.NewFreePolynomial(X, degree)
    box = 1 - x**2
    for sign in (-1, 1):
        s, _ = prog.NewSosPolynomial(X, degree - 2)
        prog.AddSosConstraint(1 + sign * p - s * box)
    prog.AddLinearCost(-p.monomial_to_coefficient_map()[Monomial(x, degree)])
    return prog


def probability():
    """min a + b + 1.25c with q − s₁x(5 − x) and q − 1 − s₂(x − 4)(5 − x) SOS, s₁, s₂ ≥ 0."""
    prog, (x,) = program(1)
    a, b, c, s1, s2 = prog.NewContinuousVariables(5, "v")
    prog.AddBoundingBoxConstraint(0, np.inf, [s1, s2])
    q = a + b * x + c * x**2
    prog.AddSosConstraint(q - s1 * x * (5 - x))
    prog.AddSosConstraint(q - 1 - s2 * (x - 4) * (5 - x))
    prog.AddLinearCost(a + b + 1.25 * c)
    return prog


def _matrix_sos(prog, G, y):
    """``yᵀ G y`` SOS: the matrix SOS condition on the symmetric polynomial matrix G."""
    m = len(y)
    prog.AddSosConstraint(sum(G[i][j] * y[i] * y[j] for i in range(m) for j in range(m)))


def sos_matrix():
    prog, (x,) = program(1)
    y = prog.NewIndeterminates(2, "y")
    _matrix_sos(prog, [[x**2 - 2 * x + 2, x], [x, x**2]], y)
    return prog


def choi():
    prog, xs = program(3)
    y = prog.NewIndeterminates(3, "y")
    _matrix_sos(prog, S._choi(*xs), y)
    return prog


def sosdemo2():
    prog, xs = program(3)
    c = prog.NewContinuousVariables(3, "c")
    f = S._sosdemo2_f(*xs)
    V = sum(ci * xi**2 for ci, xi in zip(c, xs))
    prog.AddSosConstraint(V - sum(xi**2 for xi in xs))
    prog.AddSosConstraint(-sum(V.Differentiate(xi) * fi for xi, fi in zip(xs, f)))
    return prog


def moore_greitzer(beta=0.77, delta=1e-3):
    """M − δI and −(MJ + JᵀM + Ṁ + βM) − δI SOS matrices, M of degree 4 (sosdyn's example)."""
    def build():
        from pydrake.symbolic import Variables
        prog, xs = program(2)
        X = Variables(xs)
        f = S._mg_f(*xs)
        J = [[fi.Differentiate(xj) for xj in xs] for fi in f]
        m11, m12, m22 = (prog.NewFreePolynomial(X, 4).ToExpression() for _ in range(3))
        M = [[m11, m12], [m12, m22]]
        Md = [[sum(Mij.Differentiate(xk) * fk for xk, fk in zip(xs, f)) for Mij in row] for row in M]
        G = [[-(sum(M[i][k] * J[k][j] + J[k][i] * M[k][j] for k in range(2)) + Md[i][j] + beta * M[i][j])
              - (delta if i == j else 0.0) for j in range(2)] for i in range(2)]
        y = prog.NewIndeterminates(2, "y")
        _matrix_sos(prog, [[M[i][j] - (delta if i == j else 0.0) for j in range(2)] for i in range(2)], y)
        _matrix_sos(prog, G, y)
        return prog
    return build


def dense(n):
    """The dense sextic of :func:`.sos_problems.dense_data` from its exponent/coefficient arrays."""
    _, exps, coef = S.dense_data(n)

    def build():
        from pydrake.symbolic import Expression, Monomial, Polynomial
        prog, xs = program(n)
        p = Polynomial({Monomial(xs, row): Expression(float(c)) for row, c in zip(exps, coef)})
        prog.AddSosConstraint(p)
        return prog
    return build


#: Drake builders by the problem names of :func:`.catalog.problems`.
BUILDERS = {
    "Motzkin M": feas(S.motzkin, 2),
    "Motzkin (x²+y²)·M": feas(lambda x, y: (x**2 + y**2) * S.motzkin(x, y), 2),
    "Motzkin (x²+y²+1)·M": feas(lambda x, y: (x**2 + y**2 + 1) * S.motzkin(x, y), 2),
    "Motzkin x²·M": feas(lambda x, y: x**2 * S.motzkin(x, y), 2),
    "Motzkin max γ (unbounded/ill-posed)": motzkin_max_gamma,
    "quartic form": feas(S.quartic, 2),
    "Newton example": feas(S.newton_example, 2),
    "Horn form": feas(S.horn_form(0), 5),
    "Horn form · Σx²": feas(S.horn_form(1), 5),
    "Chebyshev (max lead coef = 128)": chebyshev,
    "probability bound (1/37)": probability,
    "SOS matrix": sos_matrix,
    "Choi matrix (not SOS)": choi,
    "sosdemo2 Lyapunov": sosdemo2,
    "Moore–Greitzer β=0.77": moore_greitzer(0.77),
}


def builder(problem):
    """The Drake builder of a catalogue problem (dense ones by their size), or None."""
    if problem.group == "dense":
        return dense(problem.params["n"])
    return BUILDERS.get(problem.name)


# ---------------------------------------------------------------------- runner
def solve_once(prog) -> dict:
    """Solve with Drake's Clarabel wrapper: wall time, Clarabel's own time, status, objective."""
    from pydrake.solvers import ClarabelSolver
    t0 = now()
    res = ClarabelSolver().Solve(prog)
    wall = now() - t0
    search = float(res.get_solver_details().solve_time)
    status = STATUS.get(res.get_solution_result().name, res.get_solution_result().name)
    return {"solve": search, "canonicalize": wall - search, "status": status,
            "objective": float(res.get_optimal_cost()) if status == "optimal" else None}


def run_drake(problem, reps_for) -> dict | None:
    """Median build / canonicalise / solve of fresh Drake builds of ``problem``; ``reps_for(seconds)``
    says how many repetitions a run of that length gets. None without a builder; an error entry
    (not an exception) when Drake fails, so the benchmark goes on."""
    fn = builder(problem)
    if fn is None:
        return {"skipped": NOT_WRITTEN.get(problem.name, "no Drake version written")}
    try:
        runs, elapsed = [], 0.0
        while True:
            t0 = now()
            prog = fn()
            build = now() - t0
            run = solve_once(prog)
            run["build"] = build
            runs.append(run)
            elapsed += build + run["canonicalize"] + run["solve"]
            if len(runs) >= reps_for(elapsed / len(runs), elapsed):
                break
        out = {k: median([r[k] for r in runs]) for k in ("build", "canonicalize", "solve")}
        out.update(status=runs[-1]["status"], objective=runs[-1]["objective"], repetitions=len(runs),
                   build_min=min(r["build"] for r in runs), solver="clarabel (Drake's wrapper)")
        return out
    except Exception as exc:  # noqa: BLE001 -- report, keep benchmarking
        return {"error": f"{type(exc).__name__}: {exc}"}

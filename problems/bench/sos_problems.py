"""The known-answer SOS problems (tests/sos/test_known_answers.py) and a few larger ones, each
written twice: for sosdyn (``ours``) and for SumOfSquares.py/picos (``theirs``).

Each ``Problem`` has
* ``ours()``  -> (SOSProgram, context)   everything from plain numbers to a program ready to solve;
* ``theirs()`` -> SumOfSquares.SOSProblem built from sympy (None when not written);
* ``resolve(prog, context, rng)`` -> callable doing the re-solve path's update with new numbers
  (new polynomials prepared outside the timed region), or None;
* ``expect``: the known status ("optimal" / "infeasible" / "any").

The CDSP metric step is in :mod:`.cdsp_problems`, the Drake versions in :mod:`.drake_problems`;
:func:`.catalog.problems` lists them all.
SumOfSquares.py and sympy (the bench extra) are imported inside the ``theirs`` builders: they
are optional, and only the comparison needs them.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import sosdyn as sd
from sosdyn.poly import PolyMatrix, Polynomial, monomials_up_to
from sosdyn.sos import examples

#: Newton-polytope reduction in SumOfSquares.py (``sparse=``); the runner retries with False when
#: its hull computation fails (it needs a full-dimensional point set, e.g. not a binary form).
SPARSE = [True]


@dataclass
class Problem:
    name: str
    group: str
    ours: Callable
    theirs: Callable | None = None
    resolve: Callable | None = None
    expect: str = "optimal"
    params: dict | None = None


# ---------------------------------------------------------------------- sympy helpers (theirs)
def sympy_module():
    """sympy, imported when a SumOfSquares.py problem is built (only those need it)."""
    import sympy
    return sympy


def sos_theirs(expr_fn, nvars_names):
    """One 'expr is SOS' problem in SumOfSquares (Newton polytope reduction on: sparse=SPARSE[0])."""
    def build():
        from SumOfSquares import SOSProblem
        sp = sympy_module()
        xs = sp.symbols(nvars_names)
        prob = SOSProblem()
        prob.add_sos_constraint(sp.expand(expr_fn(*xs)), list(xs), sparse=SPARSE[0])
        return prob
    return build


# ---------------------------------------------------------------------- single-polynomial problems
def feas(expr_fn, names):
    def build():
        xs = sd.variables(names)
        prog = sd.SOSProgram()
        con = prog.add_sos(expr_fn(*xs))
        return prog, {"cons": [con], "vars": xs, "fn": expr_fn}
    return build


def scale_resolve(prog, ctx, rng):
    """New numbers, same support: p(x) -> (1 + 0.1 u) p(x) with u random (keeps the answer)."""
    con = ctx["cons"][0]
    p = con.poly
    new = Polynomial(p.vars, p.exps, p.coef * (1 + 0.1 * rng.random()), p.ids)

    def run():
        con.update(new)
    return run


def motzkin(x, y):
    return x**4 * y**2 + x**2 * y**4 + 1 - 3 * x**2 * y**2


def quartic(x, y):
    return 2 * x**4 + 2 * x**3 * y - x**2 * y**2 + 5 * y**4


def newton_example(x, y):
    return 4 * x**4 * y**6 + x**2 - x * y**2 + y**2


def horn_form(m):
    J = np.array([[1, -1, 1, 1, -1], [-1, 1, -1, 1, 1], [1, -1, 1, -1, 1],
                  [1, 1, -1, 1, -1], [-1, 1, 1, -1, 1]], dtype=float)

    def fn(*xs):
        sq = [x**2 for x in xs]
        form = sum(float(J[i, j]) * sq[i] * sq[j] for i in range(5) for j in range(5))
        return form * sum(sq) ** m if m else form
    return fn


def motzkin_max_gamma():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(motzkin(x, y) - g)
    prog.maximize(g)
    return prog, {"cons": [con]}


def motzkin_max_gamma_theirs():
    from SumOfSquares import SOSProblem
    sp = sympy_module()
    x, y, g = sp.symbols("x y g")
    prob = SOSProblem()
    prob.add_sos_constraint(sp.expand(motzkin(x, y) - g), [x, y], sparse=SPARSE[0])
    prob.set_objective("max", prob[g])
    return prob


# ---------------------------------------------------------------------- constrained problems
def chebyshev():
    return examples.chebyshev()[0], {}


def chebyshev_theirs():
    from SumOfSquares import SOSProblem, poly_variable
    sp = sympy_module()
    x = sp.symbols("x")
    prob = SOSProblem()
    p = poly_variable("p", [x], 8)
    s1, s2 = poly_variable("s", [x], 6), poly_variable("t", [x], 6)
    prob.add_sos_constraint(s1, [x], sparse=SPARSE[0])
    prob.add_sos_constraint(s2, [x], sparse=SPARSE[0])
    prob.add_sos_constraint(sp.expand(1 - p - s1 * (1 - x**2)), [x], sparse=SPARSE[0])
    prob.add_sos_constraint(sp.expand(1 + p - s2 * (1 - x**2)), [x], sparse=SPARSE[0])
    prob.set_objective("max", prob.sp_to_picos(sp.Poly(p, x).coeff_monomial(x**8)))
    return prob


def probability():
    return examples.probability_bound()[0], {}


def probability_theirs():
    from SumOfSquares import SOSProblem
    sp = sympy_module()
    x, a, b, c, s1, s2 = sp.symbols("x a b c s1 s2")
    prob = SOSProblem()
    q = a + b * x + c * x**2
    prob.add_constraint(prob[s1] >= 0)
    prob.add_constraint(prob[s2] >= 0)
    prob.add_sos_constraint(sp.expand(q - s1 * x * (5 - x)), [x], sparse=SPARSE[0])
    prob.add_sos_constraint(sp.expand(q - 1 - s2 * (x - 4) * (5 - x)), [x], sparse=SPARSE[0])
    prob.set_objective("min", prob[a] + prob[b] + 1.25 * prob[c])
    return prob


def sos_matrix():
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    con = prog.add_sos_matrix(PolyMatrix([[x**2 - 2 * x + 2, x], [x, x**2]]))
    return prog, {"cons": [con], "matrix": True}


def sos_matrix_theirs():
    from SumOfSquares import SOSProblem
    sp = sympy_module()
    x = sp.symbols("x")
    prob = SOSProblem()
    prob.add_matrix_sos_constraint(sp.Matrix([[x**2 - 2 * x + 2, x], [x, x**2]]), [x], sparse=SPARSE[0])
    return prob


def _choi(x, y, z):
    return [[x**2 + 2 * y**2, -x * y, -x * z],
            [-x * y, y**2 + 2 * z**2, -y * z],
            [-x * z, -y * z, z**2 + 2 * x**2]]


def choi():
    xs = sd.variables("x y z")
    prog = sd.SOSProgram()
    prog.add_sos_matrix(PolyMatrix(_choi(*xs)))
    return prog, {}


def choi_theirs():
    from SumOfSquares import SOSProblem
    sp = sympy_module()
    xs = sp.symbols("x y z")
    prob = SOSProblem()
    prob.add_matrix_sos_constraint(sp.Matrix(_choi(*xs)), list(xs), sparse=SPARSE[0])
    return prob


def _sosdemo2_f(x1, x2, x3):
    return [(-x1**3 - x1 * x3**2) * (x3**2 + 1),
            (-x2 - x1**2 * x2) * (x3**2 + 1),
            (-x3 + 3 * x1**2 * x3) * (x3**2 + 1) - 3 * x3]


def sosdemo2():
    x1, x2, x3 = sd.variables("x1 x2 x3")
    f = _sosdemo2_f(x1, x2, x3)
    prog = sd.SOSProgram()
    c = prog.new_var(3)
    V = c[0, 0] * x1**2 + c[1, 0] * x2**2 + c[2, 0] * x3**2
    prog.add_sos(V - (x1**2 + x2**2 + x3**2))
    prog.add_sos(-V.directional_derivative(f, ["x1", "x2", "x3"]))
    return prog, {}


def sosdemo2_theirs():
    from SumOfSquares import SOSProblem
    sp = sympy_module()
    xs = sp.symbols("x1 x2 x3")
    c = sp.symbols("c1 c2 c3")
    f = _sosdemo2_f(*xs)
    prob = SOSProblem()
    V = sum(ci * xi**2 for ci, xi in zip(c, xs))
    prob.add_sos_constraint(sp.expand(V - sum(xi**2 for xi in xs)), list(xs), sparse=SPARSE[0])
    Vdot = sum(sp.diff(V, xi) * fi for xi, fi in zip(xs, f))
    prob.add_sos_constraint(sp.expand(-Vdot), list(xs), sparse=SPARSE[0])
    return prob


_mg_f = examples.moore_greitzer_field


def moore_greitzer(beta=0.77, delta=1e-3):
    def build():
        return examples.moore_greitzer(beta, delta), {}
    return build


def moore_greitzer_theirs(beta=0.77, delta=1e-3):
    def build():
        from SumOfSquares import SOSProblem, matrix_variable
        sp = sympy_module()
        xs = sp.symbols("x1 x2")
        f = sp.Matrix(_mg_f(*xs))
        J = f.jacobian(xs)
        M = matrix_variable("m", list(xs), 4, 2)
        Mdot = sum((sp.diff(M, xi) * fi for xi, fi in zip(xs, f)), sp.zeros(2, 2))
        prob = SOSProblem()
        I2 = sp.eye(2)
        prob.add_matrix_sos_constraint((M - delta * I2).applyfunc(sp.expand), list(xs), sparse=SPARSE[0])
        G = -(M * J + J.T * M + Mdot + beta * M) - delta * I2
        prob.add_matrix_sos_constraint(G.applyfunc(sp.expand), list(xs), sparse=SPARSE[0])
        return prob
    return build


# ---------------------------------------------------------------------- dense degree-6 SOS
def dense_data(n, seed=0):
    """(sum x_i^2)^3 + z^T R R^T z / m, z all monomials of degree <= 3: a dense, strictly SOS sextic."""
    rng = np.random.default_rng(seed)
    B = monomials_up_to(n, 3)
    m = B.shape[0]
    R = rng.normal(size=(m, m))
    Q = R @ R.T / m
    names = tuple(f"x{i + 1}" for i in range(n))
    gram = Polynomial(names, (B[:, None, :] + B[None, :, :]).reshape(-1, n), Q.ravel())
    sq = sum(Polynomial(names, [np.eye(n, dtype=int)[i] * 2], [1.0]) for i in range(n)) ** 3
    p = gram + sq
    return names, p.exps, np.round(p.coef[:, 0], 10)


def dense(n):
    names, exps, coef = dense_data(n)

    def build():
        prog = sd.SOSProgram()
        con = prog.add_sos(Polynomial(names, exps, coef))
        return prog, {"cons": [con]}
    return build


def dense_theirs(n):
    names, exps, coef = dense_data(n)

    def build():
        from SumOfSquares import SOSProblem
        sp = sympy_module()
        xs = sp.symbols(" ".join(names))
        expr = sp.Add(*[float(c) * sp.Mul(*[x**int(e) for x, e in zip(xs, row) if e]) for row, c in zip(exps, coef)])
        prob = SOSProblem()
        prob.add_sos_constraint(expr, list(xs), sparse=SPARSE[0])
        return prob
    return build


def dense_resolve(n):
    def make(prog, ctx, rng):
        names, exps2, coef2 = dense_data(n, seed=int(rng.integers(1 << 30)))
        new = Polynomial(names, exps2, coef2)
        con = ctx["cons"][0]

        def run():
            con.update(new)
        return run
    return make

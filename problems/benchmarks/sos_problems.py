"""The known-answer SOS problems (tests/sos/test_known_answers.py) and a few larger ones, each
written twice: for sosdyn (``ours``) and for SumOfSquares.py/picos (``theirs``).

Each ``Problem`` has
* ``ours()``  -> (SOSProgram, context)   everything from plain numbers to a program ready to solve;
* ``theirs()`` -> SumOfSquares.SOSProblem built from sympy (None when not written);
* ``resolve(prog, context, rng)`` -> callable doing the re-solve path's update with new numbers
  (new polynomials prepared outside the timed region), or None;
* ``expect``: the known status ("optimal" / "infeasible" / "any").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

import sosdyn as sd
from problems import sos_examples as examples
from sosdyn.poly import PolyMatrix, Polynomial, monomials_up_to


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
def _sp():
    import sympy
    return sympy


def _sos_theirs(expr_fn, nvars_names):
    """One 'expr is SOS' problem in SumOfSquares (Newton polytope reduction on: sparse=SPARSE[0])."""
    def build():
        from SumOfSquares import SOSProblem
        sp = _sp()
        xs = sp.symbols(nvars_names)
        prob = SOSProblem()
        prob.add_sos_constraint(sp.expand(expr_fn(*xs)), list(xs), sparse=SPARSE[0])
        return prob
    return build


# ---------------------------------------------------------------------- single-polynomial problems
def _feas(expr_fn, names):
    def build():
        xs = sd.variables(names)
        prog = sd.SOSProgram()
        con = prog.add_sos(expr_fn(*xs))
        return prog, {"cons": [con], "vars": xs, "fn": expr_fn}
    return build


def _scale_resolve(prog, ctx, rng):
    """New numbers, same support: p(x) -> (1 + 0.1 u) p(x) with u random (keeps the answer)."""
    con = ctx["cons"][0]
    p = con.poly
    new = Polynomial(p.vars, p.exps, p.coef * (1 + 0.1 * rng.random()), p.dec)

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
    sp = _sp()
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
    sp = _sp()
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
    sp = _sp()
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
    sp = _sp()
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
    sp = _sp()
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
    sp = _sp()
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
        sp = _sp()
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
        sp = _sp()
        xs = sp.symbols(" ".join(names))
        expr = sp.Add(*[float(c) * sp.Mul(*[x**int(e) for x, e in zip(xs, row) if e]) for row, c in zip(exps, coef)])
        prob = SOSProblem()
        prob.add_sos_constraint(expr, list(xs), sparse=SPARSE[0])
        return prob
    return build


def dense_resolve(n):
    def make(prog, ctx, rng):
        names, exps, _ = dense_data(n, seed=int(rng.integers(1 << 30)))
        _, exps2, coef2 = dense_data(n, seed=int(rng.integers(1 << 30)))
        new = Polynomial(names, exps2, coef2)
        con = ctx["cons"][0]

        def run():
            con.update(new)
        return run
    return make


# ---------------------------------------------------------------------- CDSP metric step
_CDSP_CACHE: dict = {}


def cdsp_fields(shape="Leaf_1", K=6):
    """Fields (C, fexps) and parameters of a linear CDSP model fitted on a LASA shape (cached)."""
    key = (shape, K)
    if key not in _CDSP_CACHE:
        from sosdyn.lfd import CDSP, load_lasa
        model = CDSP(n_components=K, random_state=0, verify_samples=500).fit(load_lasa(shape))
        _CDSP_CACHE[key] = {"C": model.C_, "fexps": model.field_exps_, "gamma": model.gamma,
                            "eps": model.eps, "n": model.dim_}
    return _CDSP_CACHE[key]


def _metric_step(n, K, mexps, fexps, vars, gamma, eps, grow):
    """A MetricStep with the fields C set, as ``MetricStep.solve`` does before it solves.

    Returns (step, set_fields) with ``set_fields(C)`` the re-solve path's update (works with the
    compile-once families, ``set_weights``, and with the older per-constraint ``update``).
    """
    import inspect

    from sosdyn.lfd.steps import MetricStep
    if "fexps" in inspect.signature(MetricStep.__init__).parameters:
        met = MetricStep(n, K, mexps, fexps, vars, gamma, eps, grow_degree=grow)

        def set_fields(C):
            for k, con in enumerate(met.cons):
                con.set_weights(np.r_[C[k].ravel(), 1.0])
        return met, set_fields
    from sosdyn.lfd.fields import contraction_polymatrix, numeric_fields  # pragma: no cover -- old API
    met = MetricStep(n, K, mexps, vars, gamma, eps, grow_degree=grow)

    def set_fields(C, exprs=None):
        exprs = exprs or [-contraction_polymatrix(f, met.M, met.vars, met.gamma) - met.grow * met.t
                          for f in numeric_fields(C, fexps, met.vars)]
        for k, e in enumerate(exprs):
            if met.cons[k] is None:
                met.cons[k] = met.prog.add_sos_matrix(e, name=f"contraction[{k}]")
            else:
                met.cons[k].update(e)
    return met, set_fields


def cdsp_metric_step(shape="Leaf_1", K=6, metric_degree=2):
    """MetricStep (sosdyn.lfd.steps) on the fitted model's fields, built as the learner builds it."""
    def build():
        from sosdyn.lfd.fields import metric_exponents
        d = cdsp_fields(shape, K)
        n, C, fexps = d["n"], d["C"], d["fexps"]
        mexps = metric_exponents(n, metric_degree)
        vars = tuple(f"z{i + 1}" for i in range(n))
        grow = int(metric_degree + fexps.sum(axis=1).max() - 1)
        met, set_fields = _metric_step(n, K, mexps, fexps, vars, d["gamma"], d["eps"], grow)
        set_fields(C)
        return met.prog, {"met": met, "C": C, "set_fields": set_fields}
    return build


def cdsp_metric_resolve(prog, ctx, rng):
    C2 = ctx["C"] * (1 + 0.02 * rng.standard_normal(ctx["C"].shape))
    set_fields = ctx["set_fields"]

    def run():
        set_fields(C2)
    return run


def cdsp_metric_theirs(shape="Leaf_1", K=6, metric_degree=2):
    def build():
        from SumOfSquares import SOSProblem, matrix_variable
        sp = _sp()
        d = cdsp_fields(shape, K)
        n, C, fexps, gamma, eps = d["n"], d["C"], d["fexps"], d["gamma"], d["eps"]
        zs = sp.symbols(" ".join(f"z{i + 1}" for i in range(n)))
        zs = list(zs) if n > 1 else [zs]
        grow_degree = int(metric_degree + fexps.sum(axis=1).max() - 1)
        grow = (1 + sum(z**2 for z in zs)) ** (grow_degree // 2)
        M = matrix_variable("W", zs, metric_degree, n)
        t = sp.Symbol("t")
        prob = SOSProblem()
        In = sp.eye(n)
        prob.add_matrix_sos_constraint((M - eps * In).applyfunc(sp.expand), zs, sparse=SPARSE[0])
        mons = [sp.Mul(*[z**int(e) for z, e in zip(zs, row)]) for row in fexps]
        for k in range(C.shape[0]):
            f = sp.Matrix([sum(float(C[k, i, j]) * mons[j] for j in range(len(mons))) for i in range(n)])
            J = f.jacobian(zs)
            Mdot = sum((sp.diff(M, z) * f[l] for l, z in enumerate(zs)), sp.zeros(n, n))
            G = J.T * M + M * J + Mdot + gamma * M
            prob.add_matrix_sos_constraint((-G - grow * t * In).applyfunc(sp.expand), zs, sparse=SPARSE[0])
        trace0 = sum(sp.Poly(M[a, a], *zs).coeff_monomial(1) for a in range(n))
        prob.add_constraint(prob.sp_to_picos(trace0) == float(n))
        prob.add_constraint(prob[t] <= 10.0)
        prob.set_objective("max", prob[t])
        return prob
    return build


# ---------------------------------------------------------------------- the list
def problems(quick: bool = False, dense_ns=(2, 3, 4, 5, 6)) -> list:
    P = Problem
    out = [
        P("Motzkin M", "known", _feas(motzkin, "x y"), _sos_theirs(motzkin, "x y"), expect="infeasible"),
        P("Motzkin (x²+y²)·M", "known", _feas(lambda x, y: (x**2 + y**2) * motzkin(x, y), "x y"),
          _sos_theirs(lambda x, y: (x**2 + y**2) * motzkin(x, y), "x y"), _scale_resolve),
        P("Motzkin (x²+y²+1)·M", "known", _feas(lambda x, y: (x**2 + y**2 + 1) * motzkin(x, y), "x y"),
          _sos_theirs(lambda x, y: (x**2 + y**2 + 1) * motzkin(x, y), "x y"), _scale_resolve),
        P("Motzkin x²·M", "known", _feas(lambda x, y: x**2 * motzkin(x, y), "x y"),
          _sos_theirs(lambda x, y: x**2 * motzkin(x, y), "x y"), expect="infeasible"),
        P("Motzkin max γ (unbounded/ill-posed)", "known", motzkin_max_gamma, motzkin_max_gamma_theirs,
          expect="any"),
        P("quartic form", "known", _feas(quartic, "x y"), _sos_theirs(quartic, "x y"), _scale_resolve),
        P("Newton example", "known", _feas(newton_example, "x y"), _sos_theirs(newton_example, "x y"),
          _scale_resolve),
        P("Horn form", "known", _feas(horn_form(0), "x1 x2 x3 x4 x5"),
          _sos_theirs(horn_form(0), "x1 x2 x3 x4 x5"), expect="infeasible"),
        P("Horn form · Σx²", "known", _feas(horn_form(1), "x1 x2 x3 x4 x5"),
          _sos_theirs(horn_form(1), "x1 x2 x3 x4 x5"), expect="any"),
        P("Chebyshev (max lead coef = 128)", "known", chebyshev, chebyshev_theirs),
        P("probability bound (1/37)", "known", probability, probability_theirs),
        P("SOS matrix", "known", sos_matrix, sos_matrix_theirs),
        P("Choi matrix (not SOS)", "known", choi, choi_theirs, expect="infeasible"),
        P("sosdemo2 Lyapunov", "known", sosdemo2, sosdemo2_theirs),
        P("Moore–Greitzer β=0.77", "known", moore_greitzer(0.77), moore_greitzer_theirs(0.77)),
    ]
    for n in dense_ns:
        out.append(P(f"dense degree-6 SOS n={n}", "dense", dense(n), dense_theirs(n), dense_resolve(n),
                     params={"n": n}))
    out.append(P("CDSP metric step (n=2, K=6, metric deg 2)", "cdsp", cdsp_metric_step(), cdsp_metric_theirs(),
                 cdsp_metric_resolve, params={"n": 2, "K": 6, "metric_degree": 2}))
    return out

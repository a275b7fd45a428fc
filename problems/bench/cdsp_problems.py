"""The CDSP metric step as an SOS benchmark problem: ours (the learner's MetricStep on a fitted
model's fields) and theirs (the same program written for SumOfSquares.py)."""
from __future__ import annotations

from sosdyn.lfd import CDSP, load_lasa
from sosdyn.lfd.fit.contraction import contraction_degree, degree, metric_exponents, state_variables
from sosdyn.lfd.fit.params import PLAIN
from sosdyn.lfd.fit.steps import MetricStep

from .sos_problems import SPARSE

_CDSP_CACHE: dict = {}


def cdsp_fields(shape="Leaf_1", K=6):
    """Fields (C, fexps) and parameters of a linear CDSP model fitted on a LASA shape (cached)."""
    key = (shape, K)
    if key not in _CDSP_CACHE:
        model = CDSP(n_components=K, random_state=0, verify_samples=500, **PLAIN).fit(load_lasa(shape))
        _CDSP_CACHE[key] = {"C": model.C_, "fexps": model.field_exps_, "gamma": model.gamma,
                            "eps": model.eps, "n": model.dim_}
    return _CDSP_CACHE[key]


def cdsp_metric_step(shape="Leaf_1", K=6, metric_degree=2):
    """MetricStep on the fitted model's fields, built as the learner builds it; the re-solve
    path's update is ``MetricStep.set_fields`` (the compile-once families' new weights)."""
    def build():
        d = cdsp_fields(shape, K)
        n, C, fexps = d["n"], d["C"], d["fexps"]
        mexps = metric_exponents(n, metric_degree)
        grow = contraction_degree(metric_degree, degree(fexps))
        met = MetricStep(n, K, mexps, fexps, state_variables(n), d["gamma"], d["eps"], grow)
        met.set_fields(C)
        return met.prog, {"met": met, "C": C, "set_fields": met.set_fields}
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
        import sympy as sp   # optional (the bench extra), only to build SumOfSquares.py's program
        d = cdsp_fields(shape, K)
        n, C, fexps, gamma, eps = d["n"], d["C"], d["fexps"], d["gamma"], d["eps"]
        zs = sp.symbols(" ".join(f"z{i + 1}" for i in range(n)))
        zs = list(zs) if n > 1 else [zs]
        grow_degree = contraction_degree(metric_degree, degree(fexps))
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



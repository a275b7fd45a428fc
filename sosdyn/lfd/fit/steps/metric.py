"""The metric step: the fields fixed, the metric M(z) with the largest contraction margin t.

G_k is linear in the field coefficients: with unit fields u_ij (z^e_j in component i),
-(J_k^T M + M J_k + dM[f_k]) = sum_ij C[k, i, j] (-(J_u^T M + M J_u + dM[u])). The family of
component k is that sum plus the fixed term -gamma M - t g(z) I; with M - eps I SOS and
trace M(0) = n (the scale of M is free), maximise t <= t_max.

The maximiser is in general not unique (a face of the feasible set), so the solver's pick can
jump under a 1e-10 change of the data. With ``prox`` = rho > 0 the step is proximal:
maximise t - rho |w - w0|^2 over the metric coefficients w (w0: the current metric), strictly
concave in w, so its maximiser is unique and depends continuously on the fields.
"""
from __future__ import annotations

import numpy as np

from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos import SOSProgram
from ..contraction import (constant_index, contraction_polymatrix, decision_metric, margin_matrix,
                           symmetric_pairs, unit_fields)
from .common import TermTable, proximal, solve_with_fallback

FIXED = "fixed"             # the term -gamma M - t g(z) I, weight 1


class MetricStep:
    """Fields fixed: find M(z) with the largest contraction margin t (SOS feasibility).

    Terms: ("field", i, j) is -(J_u^T M + M J_u + dM[u]) for the unit field u_ij, weight
    C[k, i, j]; ``FIXED`` is -gamma M - t g(z) I, weight 1.
    """

    def __init__(self, n, K, mexps, fexps, vars, gamma, eps, grow_degree, t_max=10.0, solver="CLARABEL"):
        self.solver, self.mexps, self.n = solver, mexps, n
        self.prog = SOSProgram("metric step")
        p = mexps.shape[0]
        self.pair_ids = {pair: self.prog.new_ids(p, name=f"M{pair}") for pair in symmetric_pairs(n)}
        M = decision_metric(self.pair_ids, mexps, vars, n)
        self.t = self.prog.new_var(name="margin")
        self.prog.add_sos_matrix(M - eps * PolyMatrix.identity(n), name="metric positive")
        const = constant_index(mexps)
        trace0 = sum(Polynomial.affine([self.pair_ids[(a, a)][const]], [1.0]) for a in range(n))
        self.prog.add_eq(trace0, float(n), name="trace M(0) = n")
        self.prog.add_ge(t_max - self.t, 0.0, name="margin bound")
        self.prog.maximize(self.t)
        terms = {("field",) + key: contraction_polymatrix(u, M, vars, 0.0, scale=-1.0)
                 for key, u in unit_fields(fexps, n, vars)}
        terms[FIXED] = -gamma * M - margin_matrix(vars, n, grow_degree) * self.t
        self.table = TermTable(terms)
        self.cons = [self.table.add(self.prog, f"contraction[{k}]") for k in range(K)]

    def set_fields(self, C):
        """Set the families' weights to the numeric fields C (K, n, m)."""
        for k, con in enumerate(self.cons):
            named = {("field", i, j): C[k, i, j] for i in range(C.shape[1]) for j in range(C.shape[2])}
            con.set_weights(self.table.weights({**named, FIXED: 1.0}))

    def objective(self, W0, prox):
        """-t + prox |w - w0|^2 over the metric ids and t (w0: the coefficients of W0)."""
        ids = np.concatenate([self.pair_ids[pair] for pair in sorted(self.pair_ids)])
        center = np.concatenate([W0[a, b] for a, b in sorted(self.pair_ids)])
        order = np.argsort(ids)
        return proximal(ids[order], center[order], prox) + (-self.t)

    def solve(self, C, W0=None, prox=0.0):
        """Metric coefficients W (n, n, p) for the numeric fields C; returns (W, margin, Solution).

        ``prox`` > 0 (with the current metric W0): the proximal step of the module docstring."""
        self.set_fields(C)
        if prox > 0:
            self.prog.minimize(self.objective(W0, prox))
        else:
            self.prog.maximize(self.t)
        sol = solve_with_fallback(self.prog, self.solver)
        W = np.zeros((self.n, self.n, self.mexps.shape[0]))
        for (a, b), ids in self.pair_ids.items():
            W[a, b] = W[b, a] = sol.values_of(ids)
        return W, float(sol.values_of(self.t.ids)[0]), sol       # the solver's margin: a target for the next step

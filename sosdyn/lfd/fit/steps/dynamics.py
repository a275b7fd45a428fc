"""The dynamics step: the metric fixed, the fields by least squares under SOS contraction.

With M(z) = sum_j W[a, b, j] E_abj (unit metrics E, :func:`~sosdyn.lfd.fit.contraction.unit_metrics`)
the condition -G_k(z) - delta g_d(z) I SOS (k = 1..K) is linear in the field coefficients C,
and G_k is linear in W: the family of component k is

    sum_{(a, b, j)} W[a, b, j] (-G_k(E_abj)) + sum_d delta_d (-g_d(z) I)    SOS,

with delta_d = delta for the margin's growth degree d and 0 for the other possible degree.
"""
from __future__ import annotations

from sosdyn.sos import SOSProgram
from ..contraction import (contraction_degree, contraction_polymatrix, decision_fields, degree, margin_degree,
                           margin_matrix, unit_metrics)
from .common import LeastSquaresData, TermTable, renamed_ids, solve_with_fallback


class DynamicsStep:
    """Metric fixed: fit the fields by least squares under the SOS contraction constraints.

    Terms (:class:`~sosdyn.lfd.fit.steps.common.TermTable`): ("metric", a, b, j) is -G_k(E_abj),
    weight W[a, b, j]; ("margin", d) is -g_d(z) I, weight delta if d is the growth degree, else 0.
    ``affine_psd``: constant conditions (linear fields, constant metric) reach Clarabel as cones
    on their affine expressions (:func:`~sosdyn.lfd.fit.steps.common.solve_with_fallback`).
    """

    def __init__(self, data: LeastSquaresData, fexps, mexps, vars, gamma, margin, solver="CLARABEL",
                 affine_psd=False):
        K, n, m = data.shape
        self.solver, self.margin, self.data, self.affine_psd = solver, margin, data, affine_psd
        self.fexps, self.mexps = fexps, mexps
        self.grow_degrees = sorted({contraction_degree(0, degree(fexps)),
                                    contraction_degree(degree(mexps), degree(fexps))})
        self.prog = SOSProgram("dynamics step")
        self.ids = self.prog.new_ids(K * n * m, name="fields")
        units = unit_metrics(mexps, n, vars)
        self.unit_keys = [key for key, _ in units]
        grows = {("margin", d): margin_matrix(vars, n, d) for d in self.grow_degrees}
        self.tables, self.cons = [], []
        own = self.ids.reshape(K, n * m)        # ascending ids, as allocated
        f0 = decision_fields(own[:1].reshape(1, n, m), fexps, vars)[0]
        first = {("metric",) + key: contraction_polymatrix(f0, E, vars, gamma, scale=-1.0) for key, E in units}
        for k in range(K):                      # component k: component 0's terms, ids renamed
            terms = first if k == 0 else {name: renamed_ids(T, own[0], own[k], vars) for name, T in first.items()}
            table = TermTable({**terms, **{name: -g for name, g in grows.items()}})
            self.tables.append(table)
            self.cons.append(table.add(self.prog, f"contraction[{k}]"))
        self.prog.minimize(data.form(self.ids))

    def weights(self, W, margin, grow_degree) -> dict:
        """The family weights by name for the metric W and the margin delta g_{grow_degree}."""
        out = {("metric", a, b, j): W[a, b, j] for a, b, j in self.unit_keys}
        out.update({("margin", d): margin if d == grow_degree else 0.0 for d in self.grow_degrees})
        return out

    def solve(self, W, margin=None, grow_degree=None):
        """Fields C (K, n, m) for the numeric metric W; returns (C, Solution).

        The margin is min(margin, the step's margin) and grows like |z|^grow_degree (default:
        the degree of G for this W, :func:`~sosdyn.lfd.fit.contraction.margin_degree`).
        """
        margin = self.margin if margin is None else min(margin, self.margin)
        if grow_degree is None:
            grow_degree = margin_degree(W, self.mexps, self.fexps)
        named = self.weights(W, margin, grow_degree)
        for table, con in zip(self.tables, self.cons):
            con.set_weights(table.weights(named))
        self.last = (W, margin, grow_degree)
        sol = solve_with_fallback(self.prog, self.solver, self.affine_psd)
        return sol.values_of(self.ids).reshape(self.data.shape), sol

    def use_data(self, data: LeastSquaresData) -> DynamicsStep:
        """A new data term of the same shape (the constraints stay compiled)."""
        self.data = data
        self.prog.minimize(data.form(self.ids))
        return self

    def refit(self, data: LeastSquaresData):
        """Same metric and margins as the last solve, new data term (e.g. new GMM weights)."""
        W, margin, grow = self.use_data(data).last
        return self.solve(W, margin=margin, grow_degree=grow)

"""The ICA step: constant metric P and the fields' linear part together, by an inner convex
approximation of the BMI (Dinh, Gumussoy, Michiels & Diehl 2012).

With dJ = J - J0, dP = P - P0 the exact identity
    J^T P + P J = J^T P0 + P0 J + J0^T P + P J0 - J0^T P0 - P0 J0 + dJ^T dP + dP dJ
and Young's inequality dJ^T dP + dP dJ <= a dJ^T dJ + dP^2 / a give the sufficient
condition, by a Schur complement,
    [[-(L + gamma P) - delta g I, dJ^T, dP], [dJ, I/a, 0], [dP, 0, a I]]  SOS matrix,
convex in (J, P) and satisfied at (J0, P0): every iterate stays certified and the cost
cannot increase. g(z) = (1 + |z|^2)^(d/2), d the degree of G for a constant metric.
"""
from __future__ import annotations

import numpy as np

from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.poly.termarrays import Terms, concat_terms, terms_matmul, terms_scale, terms_transpose
from sosdyn.sos import SOSProgram, svec_to_matrix
from ..contraction import (contraction_degree, degree, field_jacobian, margin_matrix, metric_exponents, symmetric_pairs,
                           unit_fields, unit_metrics)
from .common import LeastSquaresData, TermTable, proximal, renamed_ids, solve_with_fallback


def unit_sandwich(J: Terms, a, b) -> Terms:
    """The terms of J^T E_ab + E_ab J for the terms of an n x n matrix J, E_ab the unit symmetric
    matrix with ones at (a, b) and (b, a): J^T e_u e_v^T has row u of J (transposed) as column v."""
    pieces = []
    for u, v in dict.fromkeys([(a, b), (b, a)]):         # one pair when a = b
        s = J.select(J.row == u)
        pieces.append(s._replace(row=s.col, col=np.full(s.row.size, v)))
    X = concat_terms(*pieces)
    return concat_terms(X, terms_transpose(X))


def sandwich(J: Terms, P: Terms) -> Terms:
    """The terms of J^T P + P J for the terms of n x n matrices J and P (P symmetric)."""
    X = terms_matmul(terms_transpose(J), P)
    return concat_terms(X, terms_transpose(X))


def _blocks(n, parts, vars):
    """A symmetric 3n x 3n PolyMatrix over ``vars`` with the given (row, col) blocks (PolyMatrix
    or their Terms over ``vars``; the diagonal ones symmetric), their transposes at (col, row)
    and zeros elsewhere.

    Built from the blocks' term arrays (shifted rows and columns, one sort), so the result
    keeps its terms for the SOS layer instead of being re-read entry by entry."""
    pieces = []
    for (r, c), block in parts.items():
        t = block if isinstance(block, Terms) else block.terms(vars)
        pieces.append(t._replace(row=t.row + r * n, col=t.col + c * n))
        if r != c:
            pieces.append(t._replace(row=t.col + c * n, col=t.row + r * n))
    return PolyMatrix.from_terms(concat_terms(*pieces), (3 * n, 3 * n), vars)


class ICAStep:
    """Constant metric P and the fields' linear part together, by the ICA (module docstring).

    Higher-degree field coefficients are held at their current values inside this step: their
    Jacobian grows with |z|, so the Young term a dJ^T dJ would dominate every SOS condition at
    infinity and forbid any move. The learner follows each ICA step by a dynamics step that
    moves all coefficients under the new P.

    Terms of component k (J = J_k of the decision fields, J_c the unit Jacobians, E_ab the
    unit constant metrics), and their weights at the iterate (C0, P0):

    ==========================  ==================================================  ==============
    name                        term                                                weight
    ==========================  ==================================================  ==============
    "own"                       blocks (0,0) -gamma P, (1,0) J, (2,0) P             1
    "margin"                    block (0,0) -g(z) I                                 delta
    ("P0", ab)                  blocks (0,0) -(J^T E_ab + E_ab J), (2,0) -E_ab      P0_ab
    ("J0", c)                   blocks (0,0) -(J_c^T P + P J_c), (1,0) -J_c         C0_c
                                (the (1,0) block for linear c only)
    ("J0 P0", ab)               block (0,0) E_ab                                    S_ab (below)
    "1/a", "a"                  blocks (1,1) I, (2,2) I                             1/a, a
    ==========================  ==================================================  ==============

    Parts with the same weight are one term (the blocks are disjoint, so the family's sum is
    unchanged): n(n+1)/2 + n m + n(n+1)/2 + 4 terms per component. J0l = sum_c C0_c J_c over the
    linear c is a number matrix, so the parts J_c^T E_ab + E_ab J_c (weights C0_c P0_ab) are
    summed into n(n+1)/2 terms E_ab: one per entry of the symmetric
    S = J0l^T P0 + P0 J0l = sum_{a <= b} S_ab E_ab.
    """

    def __init__(self, data: LeastSquaresData, fexps, vars, gamma, margin, eps, solver="CLARABEL"):
        K, n, m = data.shape
        self.solver, self.data, self.n = solver, data, n
        self.linear = fexps.sum(axis=1) == 1
        self.lin_exps = fexps[self.linear]                              # rows e_l: J0l = C0_lin @ lin_exps
        self.free = np.broadcast_to(self.linear, (K, n, m))
        self.prog = SOSProgram("ICA step")
        self.ids = self.prog.new_ids(int(self.free.sum()), name="linear fields")
        P = self.prog.new_psd(n, name="P")
        self.P, self.P_ids = P, P.ids
        self.prog.add_sos_matrix(P - eps * PolyMatrix.identity(n), name="metric positive")
        self.prog.add_eq(sum(P[a, a] for a in range(n)), float(n), name="trace P = n")
        E = {(a, b): E for (a, b, _), E in unit_metrics(metric_exponents(n, 0), n, vars)}
        self.pairs = symmetric_pairs(n)
        units = unit_fields(fexps, n, vars)
        Ju = [field_jacobian(u, vars) for _, u in units]                # unit Jacobians (numeric)
        self.lin_units = [c for c, ((_, j), _) in enumerate(units) if self.linear[j]]
        I = PolyMatrix.identity(n)
        grow = margin_matrix(vars, n, contraction_degree(0, degree(fexps)))
        margin_term = _blocks(n, {(0, 0): -grow}, vars)
        Pt = P.terms(vars)
        lin_units = set(self.lin_units)
        shared = {("J0", c): _blocks(n, {(0, 0): terms_scale(sandwich(Jc.terms(vars), Pt), -1.0),
                                         **({(1, 0): -Jc} if c in lin_units else {})}, vars)
                  for c, Jc in enumerate(Ju)}
        shared.update({("J0 P0", ab): _blocks(n, {(0, 0): E[ab]}, vars) for ab in self.pairs})
        shared.update({"1/a": _blocks(n, {(1, 1): I}, vars), "a": _blocks(n, {(2, 2): I}, vars)})
        self.tables, self.cons = [], []
        lin_ids = self.ids.reshape(K, -1)                               # ascending ids, as allocated
        f_lin = [Polynomial(vars, fexps[self.linear], np.hstack([np.zeros((n, 1)), np.eye(n)]), ids)
                 for ids in lin_ids[0].reshape(n, -1)]
        J = field_jacobian(f_lin, vars)
        first = {"own": _blocks(n, {(0, 0): -gamma * P, (1, 0): J, (2, 0): P}, vars)}
        first.update({("P0", ab): _blocks(n, {(0, 0): terms_scale(unit_sandwich(J.terms(vars), *ab), -1.0),
                                              (2, 0): -E[ab]}, vars) for ab in self.pairs})
        for k in range(K):                      # component k: component 0's terms, ids renamed
            own = first if k == 0 else {name: renamed_ids(T, lin_ids[0], lin_ids[k], vars) for name, T in first.items()}
            table = TermTable({"own": own["own"], "margin": margin_term,
                               **{name: T for name, T in own.items() if name != "own"}, **shared})
            self.tables.append(table)
            self.cons.append(table.add(self.prog, f"ica[{k}]"))
        self.margin = margin

    def use_data(self, data: LeastSquaresData) -> ICAStep:
        """A new data term of the same shape (the constraints stay compiled)."""
        self.data = data
        return self

    def weights(self, c0, P0, alpha) -> dict:
        """The family weights by name at the iterate (fields c0 = C0[k].ravel(), metric P0)."""
        p0 = {ab: P0[ab] for ab in self.pairs}
        out = {"own": 1.0, "margin": self.margin, "1/a": 1.0 / alpha, "a": alpha}
        out.update({("P0", ab): p0[ab] for ab in self.pairs})
        out.update({("J0", c): c0[c] for c in range(c0.size)})
        J0l = c0.reshape(self.n, -1)[:, self.linear] @ self.lin_exps
        S = J0l.T @ P0 + P0 @ J0l
        out.update({("J0 P0", ab): S[ab] for ab in self.pairs})
        return out

    def solve(self, C0, P0, alpha=1.0, prox=1e-4):
        """One ICA iterate from the certified (C0, P0); returns (C, P, Solution)."""
        for k, (table, con) in enumerate(zip(self.tables, self.cons)):
            con.set_weights(table.weights(self.weights(C0[k].ravel(), P0, alpha)))
        sv = np.array([P0[a, b] * (1.0 if a == b else np.sqrt(2.0)) for b in range(self.n) for a in range(b + 1)])
        obj = self.data.partial_form(self.ids, self.free, C0) + proximal(self.ids, C0[self.free], prox) \
            + proximal(np.sort(self.P_ids), sv[np.argsort(self.P_ids)], prox)
        self.prog.minimize(obj)
        sol = solve_with_fallback(self.prog, self.solver, affine_psd=True)   # its cones are constant
        C = C0.copy()
        C[self.free] = sol.values_of(self.ids)
        return C, svec_to_matrix(sol.values_of(self.P_ids), self.n), sol

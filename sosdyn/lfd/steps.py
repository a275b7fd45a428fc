"""The convex steps of the CDSP learner (design card: alternating convex steps).

The learning problem (18)-(20) is bilinear in the fields f_k and the metric M. Each step
fixes enough to make it convex, and each is compiled once and re-solved with new numbers
(``SOSConstraint.update``):

* :class:`DynamicsStep` -- M fixed: least squares for the field coefficients subject to
  -G_k(z) - delta I being SOS matrices (k = 1..K);
* :class:`MetricStep`   -- fields fixed: maximise the margin t with -G_k - t I SOS,
  M - eps I SOS, trace M(0) = n;
* :class:`ICAStep`      -- constant metric P and fields together: an inner convex
  approximation of the BMI (Dinh, Gumussoy, Michiels & Diehl 2012). With
  dJ = J - J0, dP = P - P0 the exact identity
      J^T P + P J = J^T P0 + P0 J + J0^T P + P J0 - J0^T P0 - P0 J0 + dJ^T dP + dP dJ
  and Young's inequality dJ^T dP + dP dJ <= a dJ^T dJ + dP^2 / a give the sufficient
  condition, by a Schur complement,
      [[-(L + gamma P) - delta I, dJ^T, dP], [dJ, I/a, 0], [dP, 0, a I]]  SOS matrix,
  convex in (J, P), satisfied at (J0, P0), so each iterate stays certified and the cost
  cannot increase.
"""
from __future__ import annotations

import numpy as np

from ..poly import PolyMatrix, Polynomial, jacobian
from ..sos import SOSProgram
from ..sos.objective import QuadraticForm
from .fields import (contraction_polymatrix, decision_fields, decision_metric, numeric_fields,
                     numeric_metric, symmetric_pairs)


class LeastSquaresData:
    """The data term of eq. (18), compressed: cost(C) = theta^T H theta - 2 g^T theta + c.

    theta = C.ravel() (K, n, m); rows of the design matrix are h_k(z_t) z_t^e_j, so the
    SDP size does not grow with the number of samples.
    """

    def __init__(self, H, Phi, Zdot):
        T, K = H.shape
        n, m = Zdot.shape[1], Phi.shape[1]
        hphi = (H[:, :, None] * Phi[:, None, :]).reshape(T, K * m)           # (T, K*m)
        gram = hphi.T @ hphi / T                                              # (K*m, K*m)
        self.H = np.zeros((K * n * m, K * n * m))
        self.g = np.zeros(K * n * m)
        idx = np.arange(K * n * m).reshape(K, n, m)
        for i in range(n):
            sel = idx[:, i, :].ravel()
            self.H[np.ix_(sel, sel)] = gram
            self.g[sel] = hphi.T @ Zdot[:, i] / T
        self.c = float((Zdot**2).sum() / T)
        self.shape = (K, n, m)

    def cost(self, C: np.ndarray) -> float:
        th = C.ravel()
        return float(th @ self.H @ th - 2 * self.g @ th + self.c)

    def form(self, ids) -> QuadraticForm:
        return QuadraticForm(self.H, -2 * self.g, self.c, ids)

    def partial_form(self, ids, free, C) -> QuadraticForm:
        """The cost as a function of the entries ``free`` (mask over theta), the rest fixed at C."""
        th = C.ravel()
        f, x = free.ravel(), ~free.ravel()
        Hff, Hfx = self.H[np.ix_(f, f)], self.H[np.ix_(f, x)]
        c = th[x] @ self.H[np.ix_(x, x)] @ th[x] - 2 * self.g[x] @ th[x] + self.c
        return QuadraticForm(Hff, 2 * Hfx @ th[x] - 2 * self.g[f], c, ids)


def _proximal(ids, center, weight) -> QuadraticForm:
    k = ids.size
    return QuadraticForm(weight * np.eye(k), -2 * weight * center, weight * center @ center, ids)


def margin_matrix(vars, n, degree):
    """(1 + |z|^2)^(degree/2) I: a margin that also holds at infinity.

    A plain margin I leaves the top-degree part of -G_k on the boundary of the PSD cone, where
    no other factor can move; growing with the degree of G keeps every iterate interior.
    """
    growth = (1.0 + sum(Polynomial((v,), [[2]], [1.0]) for v in vars)) ** (degree // 2)
    return PolyMatrix.identity(n) * growth.with_vars(vars)


def _update_or_add(prog, cons, k, expr, name):
    if cons[k] is None:
        cons[k] = prog.add_sos_matrix(expr, name=name)
    else:
        cons[k].update(expr)


class DynamicsStep:
    """Metric fixed: fit the fields by least squares under the SOS contraction constraints."""

    def __init__(self, data: LeastSquaresData, fexps, mexps, vars, gamma, margin, solver="CLARABEL"):
        K, n, m = data.shape
        self.vars, self.gamma, self.margin, self.solver, self.mexps = vars, gamma, margin, solver, mexps
        self.field_degree = int(fexps.sum(axis=1).max())
        self.prog = SOSProgram("dynamics step")
        self.ids = self.prog.new_ids(K * n * m, name="fields")
        self.fields = decision_fields(self.ids.reshape(K, n, m), fexps, vars)
        self.data = data
        self.cons = [None] * K
        self.prog.minimize(data.form(self.ids))

    def solve(self, W, center=None, prox=0.0, margin=None, grow_degree=None):
        """Fields C (K, n, m) for the numeric metric W; returns (C, Solution).

        The margin grows like |z|^grow_degree (default: the degree of G for this W).
        """
        M = numeric_metric(W, self.mexps, self.vars)
        n = W.shape[0]
        margin = self.margin if margin is None else min(margin, self.margin)
        if grow_degree is None:
            used = np.abs(W).max(axis=(0, 1)) > 0
            grow_degree = int(self.mexps[used].sum(axis=1).max()) + self.field_degree - 1
        grow = margin_matrix(self.vars, n, grow_degree)
        for k, f in enumerate(self.fields):
            G = contraction_polymatrix(f, M, self.vars, self.gamma)
            _update_or_add(self.prog, self.cons, k, -G - grow * margin, f"contraction[{k}]")
        obj = self.data.form(self.ids)
        if prox and center is not None:
            obj = obj + _proximal(self.ids, center.ravel(), prox)
        self.prog.minimize(obj)
        sol = self.prog.solve(solver=self.solver, raise_on_failure=True)
        return sol.values_of(self.ids).reshape(self.data.shape), sol


class MetricStep:
    """Fields fixed: find M(z) with the largest contraction margin t (SOS feasibility)."""

    def __init__(self, n, K, mexps, vars, gamma, eps, grow_degree, t_max=10.0, solver="CLARABEL"):
        self.vars, self.gamma, self.solver, self.mexps, self.n = vars, gamma, solver, mexps, n
        self.grow = margin_matrix(vars, n, grow_degree)
        self.prog = SOSProgram("metric step")
        p = mexps.shape[0]
        self.pair_ids = {pair: self.prog.new_ids(p, name=f"M{pair}") for pair in symmetric_pairs(n)}
        self.M = decision_metric(self.pair_ids, mexps, vars, n)
        self.t = self.prog.new_var(name="margin")
        self.prog.add_sos_matrix(self.M - eps * PolyMatrix.identity(n), name="metric positive")
        const = int(np.flatnonzero(mexps.sum(axis=1) == 0)[0])
        trace0 = sum(Polynomial.affine([self.pair_ids[(a, a)][const]], [1.0]) for a in range(n))
        self.prog.add_eq(trace0, float(n), name="trace M(0) = n")
        self.prog.add_ge(t_max - self.t, 0.0, name="margin bound")
        self.prog.maximize(self.t)
        self.cons = [None] * K

    def solve(self, C, fexps):
        """Metric coefficients W (n, n, p) for the numeric fields C; returns (W, margin, Solution)."""
        n = self.n
        for k, f in enumerate(numeric_fields(C, fexps, self.vars)):
            G = contraction_polymatrix(f, self.M, self.vars, self.gamma)
            _update_or_add(self.prog, self.cons, k, -G - self.grow * self.t, f"contraction[{k}]")
        sol = self.prog.solve(solver=self.solver, raise_on_failure=True)
        W = np.zeros((n, n, self.mexps.shape[0]))
        for (a, b), ids in self.pair_ids.items():
            W[a, b] = W[b, a] = sol.values_of(ids)
        return W, sol.value(self.t), sol


class ICAStep:
    """Constant metric P and the fields' linear part together, by the ICA (module docstring).

    Higher-degree field coefficients are held at their current values inside this step: their
    Jacobian grows with |z|, so the Young term a dJ^T dJ would dominate every SOS condition at
    infinity and forbid any move. The estimator follows each ICA step by a dynamics step that
    moves all coefficients under the new P.
    """

    def __init__(self, data: LeastSquaresData, fexps, vars, gamma, margin, eps, solver="CLARABEL"):
        K, n, m = data.shape
        self.vars, self.gamma, self.margin, self.solver, self.fexps = vars, gamma, margin, solver, fexps
        self.data, self.n = data, n
        self.linear = fexps.sum(axis=1) == 1
        self.free = np.broadcast_to(self.linear, (K, n, m))
        self.grow = margin_matrix(vars, n, int(fexps.sum(axis=1).max() - 1))
        self.prog = SOSProgram("ICA step")
        self.ids = self.prog.new_ids(int(self.free.sum()), name="linear fields")
        self.P = self.prog.new_psd(n, name="P")
        self.P_ids = self.P.dec
        self.prog.add_sos_matrix(self.P - eps * PolyMatrix.identity(n), name="metric positive")
        self.prog.add_eq(sum(self.P[a, a] for a in range(n)), float(n), name="trace P = n")
        self.cons = [None] * K

    def solve(self, C0, P0, alpha=1.0, prox=1e-4):
        """One ICA iterate from the certified (C0, P0); returns (C, P, Solution)."""
        n, K = self.n, C0.shape[0]
        P0m = PolyMatrix(P0)
        I = PolyMatrix.identity(n)
        Z = PolyMatrix(np.zeros((n, n)))
        lin_ids = self.ids.reshape(K, n, -1)
        fixed = C0 * ~self.free
        for k, f0 in enumerate(numeric_fields(C0, self.fexps, self.vars)):
            f_fixed = numeric_fields(fixed[k:k + 1], self.fexps, self.vars)[0]
            f = [Polynomial(self.vars, self.fexps[self.linear],
                            np.hstack([np.zeros((n, 1)), np.eye(n)]), lin_ids[k, i]) + f_fixed[i]
                 for i in range(n)]
            J, J0 = jacobian(f, self.vars), jacobian(f0, self.vars)
            L = J.T @ P0m + P0m @ J + J0.T @ self.P + self.P @ J0 - J0.T @ P0m - P0m @ J0 + self.gamma * self.P
            dJ, dP = J - J0, self.P - P0m
            S = np.block([[(-L - self.grow * self.margin).entries, dJ.T.entries, dP.entries],
                          [dJ.entries, (I * (1.0 / alpha)).entries, Z.entries],
                          [dP.entries, Z.entries, (I * alpha).entries]])
            _update_or_add(self.prog, self.cons, k, PolyMatrix(S), f"ica[{k}]")
        p0 = np.array([P0[a, b] * (1.0 if a == b else np.sqrt(2.0)) for b in range(n) for a in range(b + 1)])
        obj = self.data.partial_form(self.ids, self.free, C0) + _proximal(self.ids, C0[self.free], prox) \
            + _proximal(np.sort(self.P_ids), _svec_order(p0, self.P_ids), prox)
        self.prog.minimize(obj)
        sol = self.prog.solve(solver=self.solver, raise_on_failure=True)
        C = C0.copy()
        C[self.free] = sol.values_of(self.ids)
        return C, sol.value(self.P), sol


def _svec_order(values, ids):
    """Reorder svec values (given in ids' order) to sorted-id order."""
    return np.asarray(values)[np.argsort(ids)]


def certify(C, fexps, W, mexps, vars, gamma, eps, solver="CLARABEL"):
    """Final certificate for numeric (C, W): -G_k SOS matrices and M - eps I SOS matrix.

    Returns the Solution (its constraints carry the Gram matrices).
    """
    prog = SOSProgram("certificate")
    n = W.shape[0]
    M = numeric_metric(W, mexps, vars)
    prog.add_sos_matrix(M - eps * PolyMatrix.identity(n), name="M - eps I")
    for k, f in enumerate(numeric_fields(C, fexps, vars)):
        prog.add_sos_matrix(-contraction_polymatrix(f, M, vars, gamma), name=f"-G[{k}]")
    return prog.solve(solver=solver)

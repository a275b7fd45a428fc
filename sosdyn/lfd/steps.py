"""The convex steps of the CDSP learner (design card: alternating convex steps).

The learning problem (18)-(20) is bilinear in the fields f_k and the metric M. Each step
fixes enough to make it convex, and each is compiled once: its SOS constraints are linear
families sum_t w_t T_t whose terms T_t are expanded and matched at construction, so a
re-solve with new numbers only recomputes the weights (``add_sos_matrix_family``).

* :class:`DynamicsStep` -- M fixed: least squares for the field coefficients subject to
  -G_k(z) - delta g(z) I being SOS matrices (k = 1..K);
* :class:`MetricStep`   -- fields fixed: maximise the margin t with -G_k - t g(z) I SOS,
  M - eps I SOS, trace M(0) = n;
* :class:`ICAStep`      -- constant metric P and the fields' linear part together: an inner
  convex approximation of the BMI (Dinh, Gumussoy, Michiels & Diehl 2012). With
  dJ = J - J0, dP = P - P0 the exact identity
      J^T P + P J = J^T P0 + P0 J + J0^T P + P J0 - J0^T P0 - P0 J0 + dJ^T dP + dP dJ
  and Young's inequality dJ^T dP + dP dJ <= a dJ^T dJ + dP^2 / a give the sufficient
  condition, by a Schur complement,
      [[-(L + gamma P) - delta g I, dJ^T, dP], [dJ, I/a, 0], [dP, 0, a I]]  SOS matrix,
  convex in (J, P) and satisfied at (J0, P0): every iterate stays certified and the cost
  cannot increase.

g(z) = (1 + |z|^2)^(d/2) is the margin's growth (:func:`margin_matrix`).
"""
from __future__ import annotations

import numpy as np

from ..poly import PolyMatrix, Polynomial, jacobian
from ..sos import SOSProgram
from ..sos.objective import QuadraticForm
from .fields import (contraction_polymatrix, decision_fields, decision_metric, symmetric_pairs,
                     unit_fields, unit_metrics)


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


def margin_matrix(vars, n, degree):
    """(1 + |z|^2)^(degree/2) I: a margin that also holds at infinity.

    A plain margin I leaves the top-degree part of -G_k on the boundary of the PSD cone, where
    no other factor can move; growing with the degree of G keeps every iterate interior.
    """
    growth = (1.0 + sum(Polynomial((v,), [[2]], [1.0]) for v in vars)) ** (degree // 2)
    return PolyMatrix.identity(n) * growth.with_vars(vars)


def _proximal(ids, center, weight) -> QuadraticForm:
    k = ids.size
    return QuadraticForm(weight * np.eye(k), -2 * weight * center, weight * center @ center, ids)


def solve_with_fallback(prog, solver):
    """Solve; if the solver fails numerically (not: proves infeasibility), retry once with SCS.

    The fallback is stated in ``sol.info["fallback"]`` (and so in the learner's history_).
    """
    sol = prog.solve(solver=solver)
    if sol.usable or sol.status in ("infeasible", "unbounded") or solver == "SCS":
        return sol.raise_for_status()
    first = f"{solver}: {sol.status} ({sol.raw_status})"
    retry = prog.solve(solver="SCS", backend="cvxpy", eps=1e-9, max_iters=200_000)
    retry.info["fallback"] = f"SCS after {first}"
    return retry.raise_for_status()


def _degree(exps) -> int:
    return int(exps.sum(axis=1).max())


class DynamicsStep:
    """Metric fixed: fit the fields by least squares under the SOS contraction constraints.

    Family terms of component k: -G_k(E_j) for each unit metric E_j (weight W_j), and the
    margin -g_d(z) I for each possible growth degree d (weight delta or 0).
    """

    def __init__(self, data: LeastSquaresData, fexps, mexps, vars, gamma, margin, solver="CLARABEL"):
        K, n, m = data.shape
        self.solver, self.margin, self.data = solver, margin, data
        self.field_degree = _degree(fexps)
        self.mexps = mexps
        self.grow_degrees = sorted({self.field_degree - 1, _degree(mexps) + self.field_degree - 1})
        self.prog = SOSProgram("dynamics step")
        self.ids = self.prog.new_ids(K * n * m, name="fields")
        units = unit_metrics(mexps, n, vars)
        self.unit_index = [key for key, _ in units]
        grows = [margin_matrix(vars, n, d) for d in self.grow_degrees]
        self.cons = []
        for k, f in enumerate(decision_fields(self.ids.reshape(K, n, m), fexps, vars)):
            terms = [-contraction_polymatrix(f, E, vars, gamma) for _, E in units] + [-g for g in grows]
            self.cons.append(self.prog.add_sos_matrix_family(terms, np.zeros(len(terms)), name=f"contraction[{k}]"))
        self.prog.minimize(data.form(self.ids))

    def solve(self, W, margin=None, grow_degree=None):
        """Fields C (K, n, m) for the numeric metric W; returns (C, Solution).

        The margin grows like |z|^grow_degree (default: the degree of G for this W).
        """
        margin = self.margin if margin is None else min(margin, self.margin)
        if grow_degree is None:
            used = np.abs(W).max(axis=(0, 1)) > 0
            grow_degree = _degree(self.mexps[used]) + self.field_degree - 1
        w = np.array([W[a, b, j] for a, b, j in self.unit_index]
                     + [margin if d == grow_degree else 0.0 for d in self.grow_degrees])
        for con in self.cons:
            con.set_weights(w)
        self.last = (W, margin, grow_degree)
        sol = solve_with_fallback(self.prog, self.solver)
        return sol.values_of(self.ids).reshape(self.data.shape), sol

    def refit(self, data: LeastSquaresData):
        """Same metric and margins as the last solve, new data term (e.g. new GMM weights)."""
        self.data = data
        self.prog.minimize(data.form(self.ids))
        W, margin, grow = self.last
        return self.solve(W, margin=margin, grow_degree=grow)


class MetricStep:
    """Fields fixed: find M(z) with the largest contraction margin t (SOS feasibility).

    Family terms of component k: -(J_u^T M + M J_u + dM[u]) for each unit field u (weight C_k,u)
    and the fixed term -gamma M - t g(z) I (weight 1).
    """

    def __init__(self, n, K, mexps, fexps, vars, gamma, eps, grow_degree, t_max=10.0, solver="CLARABEL"):
        self.solver, self.mexps, self.n = solver, mexps, n
        self.prog = SOSProgram("metric step")
        p = mexps.shape[0]
        self.pair_ids = {pair: self.prog.new_ids(p, name=f"M{pair}") for pair in symmetric_pairs(n)}
        M = decision_metric(self.pair_ids, mexps, vars, n)
        self.t = self.prog.new_var(name="margin")
        self.prog.add_sos_matrix(M - eps * PolyMatrix.identity(n), name="metric positive")
        const = int(np.flatnonzero(mexps.sum(axis=1) == 0)[0])
        trace0 = sum(Polynomial.affine([self.pair_ids[(a, a)][const]], [1.0]) for a in range(n))
        self.prog.add_eq(trace0, float(n), name="trace M(0) = n")
        self.prog.add_ge(t_max - self.t, 0.0, name="margin bound")
        self.prog.maximize(self.t)
        units = unit_fields(fexps, n, vars)
        fixed = -gamma * M - margin_matrix(vars, n, grow_degree) * self.t
        terms = [-contraction_polymatrix(u, M, vars, 0.0) for _, u in units] + [fixed]
        self.cons = [self.prog.add_sos_matrix_family(terms, np.zeros(len(terms)), name=f"contraction[{k}]")
                     for k in range(K)]

    def solve(self, C):
        """Metric coefficients W (n, n, p) for the numeric fields C; returns (W, margin, Solution)."""
        for k, con in enumerate(self.cons):
            con.set_weights(np.r_[C[k].ravel(), 1.0])
        sol = solve_with_fallback(self.prog, self.solver)
        W = np.zeros((self.n, self.n, self.mexps.shape[0]))
        for (a, b), ids in self.pair_ids.items():
            W[a, b] = W[b, a] = sol.values_of(ids)
        return W, sol.value(self.t), sol


def _blocks(n, parts):
    """A symmetric 3n x 3n PolyMatrix with the given (row, col) blocks and their transposes."""
    out = np.empty((3 * n, 3 * n), dtype=object)
    zero = PolyMatrix(np.zeros((n, n)))
    for r in range(3):
        for c in range(3):
            block = parts.get((r, c)) or (parts[(c, r)].T if (c, r) in parts else zero)
            out[r * n:(r + 1) * n, c * n:(c + 1) * n] = block.entries
    return PolyMatrix(out)


class ICAStep:
    """Constant metric P and the fields' linear part together, by the ICA (module docstring).

    Higher-degree field coefficients are held at their current values inside this step: their
    Jacobian grows with |z|, so the Young term a dJ^T dJ would dominate every SOS condition at
    infinity and forbid any move. The estimator follows each ICA step by a dynamics step that
    moves all coefficients under the new P.
    """

    def __init__(self, data: LeastSquaresData, fexps, vars, gamma, margin, eps, solver="CLARABEL"):
        K, n, m = data.shape
        self.solver, self.data, self.n = solver, data, n
        self.linear = fexps.sum(axis=1) == 1
        self.free = np.broadcast_to(self.linear, (K, n, m))
        self.prog = SOSProgram("ICA step")
        self.ids = self.prog.new_ids(int(self.free.sum()), name="linear fields")
        P = self.prog.new_psd(n, name="P")
        self.P, self.P_ids = P, P.dec
        self.prog.add_sos_matrix(P - eps * PolyMatrix.identity(n), name="metric positive")
        self.prog.add_eq(sum(P[a, a] for a in range(n)), float(n), name="trace P = n")
        E = [E for _, E in unit_metrics(np.zeros((1, n), dtype=np.int64), n, vars)]
        self.pairs = symmetric_pairs(n)
        units = unit_fields(fexps, n, vars)
        Ju = [jacobian(u, vars) for _, u in units]                      # unit Jacobians (numeric)
        self.lin_units = [c for c, ((_, j), _) in enumerate(units) if self.linear[j]]
        I = PolyMatrix.identity(n)
        grow = margin_matrix(vars, n, _degree(fexps) - 1)
        shared = [_blocks(n, {(0, 0): -grow})]                                               # margin
        shared_p0 = [_blocks(n, {(0, 0): -(Jc.T @ P + P @ Jc)}) for Jc in Ju]                # C0_c
        shared_p0 += [_blocks(n, {(0, 0): Ju[c].T @ Eab + Eab @ Ju[c]})                      # C0_c P0_ab
                      for c in self.lin_units for Eab in E]
        shared_p0 += [_blocks(n, {(1, 0): -Ju[c]}) for c in self.lin_units]                   # C0_c
        shared_p0 += [_blocks(n, {(2, 0): -Eab}) for Eab in E]                                # P0_ab
        shared_p0 += [_blocks(n, {(1, 1): I}), _blocks(n, {(2, 2): I})]                       # 1/a, a
        self.cons = []
        lin_ids = self.ids.reshape(K, n, -1)
        for k in range(K):
            f_lin = [Polynomial(vars, fexps[self.linear], np.hstack([np.zeros((n, 1)), np.eye(n)]), lin_ids[k, i])
                     for i in range(n)]
            J = jacobian(f_lin, vars)
            own = [_blocks(n, {(0, 0): -gamma * P, (1, 0): J, (2, 0): P})]                  # weight 1
            own_p0 = [_blocks(n, {(0, 0): -(J.T @ Eab + Eab @ J)}) for Eab in E]            # P0_ab
            terms = own + shared + own_p0 + shared_p0
            self.cons.append(self.prog.add_sos_matrix_family(terms, np.zeros(len(terms)), name=f"ica[{k}]"))
        self.margin = margin

    def solve(self, C0, P0, alpha=1.0, prox=1e-4):
        """One ICA iterate from the certified (C0, P0); returns (C, P, Solution)."""
        p0 = np.array([P0[a, b] for a, b in self.pairs])
        for k, con in enumerate(self.cons):
            c0 = C0[k].ravel()
            w = np.concatenate([[1.0, self.margin], p0, c0,
                                [c0[c] * pab for c in self.lin_units for pab in p0],
                                c0[self.lin_units], p0, [1.0 / alpha, alpha]])
            con.set_weights(w)
        sv = np.array([P0[a, b] * (1.0 if a == b else np.sqrt(2.0)) for b in range(self.n) for a in range(b + 1)])
        obj = self.data.partial_form(self.ids, self.free, C0) + _proximal(self.ids, C0[self.free], prox) \
            + _proximal(np.sort(self.P_ids), sv[np.argsort(self.P_ids)], prox)
        self.prog.minimize(obj)
        sol = solve_with_fallback(self.prog, self.solver)
        C = C0.copy()
        C[self.free] = sol.values_of(self.ids)
        return C, sol.value(self.P), sol


def certify(C, fexps, W, mexps, vars, gamma, eps, solver="CLARABEL"):
    """Final certificate for numeric (C, W): -G_k SOS matrices and M - eps I SOS matrix.

    Returns the Solution (its constraints carry the Gram matrices).
    """
    from .fields import numeric_fields, numeric_metric
    prog = SOSProgram("certificate")
    n = W.shape[0]
    M = numeric_metric(W, mexps, vars)
    prog.add_sos_matrix(M - eps * PolyMatrix.identity(n), name="M - eps I")
    for k, f in enumerate(numeric_fields(C, fexps, vars)):
        prog.add_sos_matrix(-contraction_polymatrix(f, M, vars, gamma), name=f"-G[{k}]")
    return prog.solve(solver=solver)

"""What the convex steps share: the compressed data term, named term tables, the solve policy.

Each step is compiled once: its SOS constraints are linear families sum_t w_t T_t whose terms
T_t are expanded and matched at construction, so a re-solve with new numbers only recomputes
the weights (``add_sos_matrix_family`` + ``set_weights``). A :class:`TermTable` names the
terms, so the weights are given by name and their order lives in one place.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sosdyn.errors import InputError
from sosdyn.poly import PolyMatrix
from sosdyn.sos import QuadraticForm
from sosdyn.sos.rigorous import ANSWERED

TIGHT_CLARABEL = dict(tol_feas=1e-10, tol_gap_abs=1e-10, tol_gap_rel=1e-10)
#: Clarabel factors the KKT systems of the constant-cone steps (``affine_psd``: linear fields, constant
#: metric) on one thread: they are small (PSD blocks of at most 3n x 3n; an ICA step at n = 7 has ~1700
#: rows), so a second thread costs more in synchronisation than it gains (issue 26: ~20 % of an ICA
#: solve at n = 7). Their answers were the same bit for bit (fits at n = 2, 7 and the 7-D joint-space
#: demos); the larger Gram blocks of higher-degree steps keep Clarabel's default (there the thread
#: count changes the round-off).
ONE_THREAD = dict(max_threads=1)
FALLBACK_SOLVER = "SCS"
FALLBACK_SETTINGS = dict(backend="cvxpy", eps=1e-9, max_iters=200_000)


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


class TermTable:
    """The terms of one compile-once family, by name (an ordered mapping name -> PolyMatrix).

    ``add(prog, name)`` declares the family; ``weights({name: w})`` is the weight vector in the
    table's order, refusing a missing or unknown name.
    """

    def __init__(self, terms: Mapping):
        self.names = tuple(terms)
        self.terms = list(terms.values())

    def add(self, prog, name):
        return prog.add_sos_matrix_family(self.terms, np.zeros(len(self.terms)), name=name)

    def weights(self, values: Mapping) -> np.ndarray:
        if len(values) != len(self.names) or any(k not in values for k in self.names):
            missing = [k for k in self.names if k not in values][:3]
            unknown = [k for k in values if k not in set(self.names)][:3]
            raise InputError(f"family weights must name every term exactly once: missing {missing}, "
                             f"unknown {unknown}. Try: one weight per name in the step's term table.")
        return np.array([values[k] for k in self.names], dtype=float)


def renamed_ids(P: PolyMatrix, old, new, vars) -> PolyMatrix:
    """P with every decision id old[i] renamed new[i] (``old`` sorted, ``new`` in the same order;
    other ids kept): component k's copy of a term that is linear in component 0's coefficients,
    made from P's term arrays instead of by repeating the polynomial algebra."""
    t = P.terms(vars)
    pos = np.minimum(np.searchsorted(old, t.did), old.size - 1)
    hit = old[pos] == t.did
    return PolyMatrix.from_terms(t._replace(did=np.where(hit, new[pos], t.did)), P.shape, vars)


def proximal(ids, center, weight) -> QuadraticForm:
    """weight * |x - center|^2 over the decision ids ``ids``."""
    k = ids.size
    return QuadraticForm(weight * np.eye(k), -2 * weight * center, weight * center @ center, ids)


def solve_with_fallback(prog, solver, affine_psd=False):
    """Solve with ``solver``; if its answer is not usable, retry, else raise.

    ``affine_psd``: Clarabel (direct back end) gets the PSD blocks fixed by their equality rows
    as cones on affine expressions (:func:`~sosdyn.sos.conic.affine_cones`); the SCS retry never.
    With ``affine_psd``, Clarabel runs on one thread (``ONE_THREAD``).

    Usable means the whole certificate passed the independent check (``sol.usable``). A proof
    of infeasibility (or unboundedness) is an answer, not a numerical failure, and is raised as
    it is; so is any failure of SCS itself. Otherwise:

    1. a Clarabel answer that fails the check (status optimal or optimal_inaccurate, numbers
       slightly off) is re-solved once by Clarabel with tighter tolerances (``TIGHT_CLARABEL``);
    2. if that is not usable either, or Clarabel crashed or reported a solver error, SCS through
       cvxpy with tight tolerances (``FALLBACK_SETTINGS``) gets one try, and whatever it gives is
       raised if not usable.

    A retry that is used is stated in ``sol.info["fallback"]`` (and so in the learner's history_).
    The library's own retries (``SOSProgram.solve(retry=...)``, :mod:`sosdyn.sos.remedies`) are
    off here: this is the learner's retry policy, and its fits stay what they were.
    """
    clarabel = solver.upper() == "CLARABEL"
    direct = {"retry": False, **({"affine_psd": True, **ONE_THREAD} if affine_psd and clarabel else {})}
    sol = prog.solve(solver=solver, **direct)
    if sol.usable or sol.status in ("infeasible", "unbounded") or solver == FALLBACK_SOLVER:
        return sol.raise_for_status()
    first = f"{solver}: {sol.status} ({sol.raw_status})"
    if clarabel and sol.status in ANSWERED:
        tight = prog.solve(solver=solver, **TIGHT_CLARABEL, **direct)
        if tight.usable:
            tight.info["fallback"] = f"{solver} with tighter tolerances after {first}"
            return tight
    retry = prog.solve(solver=FALLBACK_SOLVER, retry=False, **FALLBACK_SETTINGS)
    retry.info["fallback"] = f"{FALLBACK_SOLVER} after {first}"
    return retry.raise_for_status()

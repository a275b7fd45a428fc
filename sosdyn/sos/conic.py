"""Lowering an SOSProgram to one standard-form conic problem.

    minimise    x^T P x + q^T x + c
    subject to  A_eq x = b_eq,   A_ge x >= b_ge,   svec^-1(x[block]) >= 0 for each PSD block

x stacks every decision id of the program (free scalars and Gram svec entries) in
creation order. With ``scale`` each row of A_eq / A_ge is divided by its largest entry,
so coefficients of very different magnitude reach the solver equilibrated.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, PolynomialError
from ..poly import PolyMatrix, Polynomial
from .objective import QuadraticForm, affine_rows, is_cvxpy


@dataclass
class ConicData:
    ids: np.ndarray
    A_eq: sp.csc_matrix
    b_eq: np.ndarray
    A_ge: sp.csc_matrix
    b_ge: np.ndarray
    psd: list            # [(positions, size)]
    P: sp.csc_matrix | None
    q: np.ndarray
    c: float
    sense: str           # "min" | "max" (P, q, c already negated for "max")
    scaled: bool
    infeasible_reason: str | None
    seconds: float

    @property
    def n(self) -> int:
        return self.ids.size

    def sizes(self) -> dict:
        return {"variables": int(self.n), "equalities": int(self.A_eq.shape[0]),
                "inequalities": int(self.A_ge.shape[0]),
                "psd_blocks": [int(b) for _, b in self.psd], "nnz": int(self.A_eq.nnz + self.A_ge.nnz)}


def positions(ids: np.ndarray, wanted: np.ndarray, what: str = "expression") -> np.ndarray:
    """Positions of decision ids in the program's vector; error if one is foreign."""
    pos = np.searchsorted(ids, wanted)
    pos = np.minimum(pos, max(ids.size - 1, 0))
    if wanted.size and (ids.size == 0 or not np.array_equal(ids[pos], wanted)):
        raise PolynomialError(f"{what} uses decision variables that were not declared in this "
                              "program (made by another SOSProgram?)")
    return pos


def _stack(ids, parts, kind, scale):
    parts = [p for p in parts if p.kind == kind]
    n_rows, r, c, v, rhs = 0, [], [], [], []
    for p in parts:
        r.append(p.rows + n_rows)
        c.append(positions(ids, p.ids, f"constraint {p.name!r}"))
        v.append(p.vals)
        rhs.append(p.rhs)
        n_rows += p.rhs.size
    cat = lambda xs, dt: np.concatenate(xs) if xs else np.zeros(0, dtype=dt)  # noqa: E731
    A = sp.csr_matrix((cat(v, float), (cat(r, np.int64), cat(c, np.int64))), shape=(n_rows, ids.size))
    b = cat(rhs, float)
    empty = np.diff(A.indptr) == 0
    if kind == "eq":      # 0 = 0 rows carry nothing; 0 = b != 0 rows are caught as infeasible
        keep = ~(empty & (b == 0))
        A, b = A[keep], b[keep]
    if scale and A.nnz:
        norms = np.maximum(abs(A).max(axis=1).toarray().ravel(), 1e-300)
        norms[np.diff(A.indptr) == 0] = 1.0
        A = sp.diags(1.0 / norms) @ A
        b = b / norms
    return A.tocsc(), b


def _objective(program, ids):
    if program.objective is None:
        return None, np.zeros(ids.size), 0.0, "min"
    sense, expr = program.objective
    if is_cvxpy(expr):
        return None, np.zeros(ids.size), 0.0, sense
    sign = -1.0 if sense == "max" else 1.0
    q = np.zeros(ids.size)
    if isinstance(expr, QuadraticForm):
        pos = positions(ids, expr.dec, "objective")
        P = sp.coo_matrix(expr.P)
        P = sp.csc_matrix((P.data, (pos[P.row], pos[P.col])), shape=(ids.size, ids.size))
        q[pos] = expr.q
        return P, q, expr.c, sense
    c0, C, dec = affine_rows([expr])
    q[positions(ids, dec, "objective")] = sign * C[0]
    return None, q, sign * c0[0], sense


def assemble(program, scale: bool = True) -> ConicData:
    """Build the :class:`ConicData` of ``program`` (sparse, numeric, no cvxpy)."""
    t0 = time.perf_counter()
    ids = program.ids
    rows = [c.rows for c in program.sos_constraints] + list(program.linear)
    A_eq, b_eq = _stack(ids, rows, "eq", scale)
    A_ge, b_ge = _stack(ids, rows, "ge", scale)
    psd = [(positions(ids, b.ids), b.size) for b in program.psd_blocks]
    P, q, c, sense = _objective(program, ids)
    reasons = [c.infeasible_reason for c in program.sos_constraints if c.infeasible_reason]
    return ConicData(ids, A_eq, b_eq, A_ge, b_ge, psd, P, q, c, sense, scale,
                     reasons[0] if reasons else None, time.perf_counter() - t0)


def cvxpy_block_vars(program) -> list:
    """One cvxpy Variable per declared block (created once, reused by every solve)."""
    import cvxpy as cp
    out = []
    for b in program.blocks:
        key = int(b.ids[0]) if b.ids.size else id(b)
        if key not in program._cvx_vars:
            program._cvx_vars[key] = cp.Variable(b.ids.size, name=b.name)
        out.append(program._cvx_vars[key])
    return out


def cvxpy_affine(program, item):
    """cvxpy expression c0 + C x[pos] of degree-0 affine polynomial(s) of ``program``."""
    import cvxpy as cp
    if isinstance(item, PolyMatrix):
        rows = [[cvxpy_affine(program, p) for p in row] for row in item.entries]
        return cp.bmat(rows)
    if not isinstance(item, Polynomial):
        raise InputError(f"expr() takes a Polynomial or PolyMatrix, got {type(item).__name__}")
    c0, C, dec = affine_rows([item])
    if not dec.size:
        return cp.Constant(c0[0])
    x = cp.hstack(cvxpy_block_vars(program))
    pos = positions(program.ids, dec, "expression")
    return c0[0] + C[0] @ x[pos]

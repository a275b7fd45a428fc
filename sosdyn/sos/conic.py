"""Lowering an SOSProgram to one standard-form conic problem.

    minimise    x^T P x + q^T x + c
    subject to  A_eq x = b_eq,   A_ge x >= b_ge,   svec^-1(x[block]) >= 0 for each PSD block,
                (G x)[3k] >= ||(G x)[3k+1 : 3k+3]||_2 for each second-order cone k (SDSOS blocks)

x stacks every decision id of the program (free scalars and Gram svec entries) in
creation order. With ``scale`` each row of A_eq / A_ge is divided by its largest entry,
so coefficients of very different magnitude reach the solver equilibrated.

Admissible data (:func:`check_data`, before any solver sees it): every equality row's
right-hand side, relative to the row's largest coefficient, is at most ``MAX_RHS`` = 1e8,
and the objective is finite. Interior-point solvers work to absolute tolerances near 1e-8
on data of order 1; measured with Clarabel, right-hand sides of 3e9 relative to their rows
already give wrong answers (a feasible x^4 + 3e9 x^2 + 1 - g reported infeasible) and 1e7
to 1e9 give solver errors on some problems, while the learner's and the known-answer
problems stay below 4e4. Larger numbers mean the variables are badly scaled.

cvxpy is imported only inside the cvxpy helpers (``cvxpy_block_vars``, ``cvxpy_affine``): it
takes about 3 s to import, and only programs with cvxpy constraints or objectives need it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, PolynomialError
from ..poly import PolyMatrix, Polynomial
from .csc import column_of_entries, csc, from_triplets
from .objective import QuadraticForm, affine_rows, is_cvxpy

MAX_RHS = 1e8


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
    rhs_ratio: float = 0.0      # largest |b_i| / max_j |A_ij| over the equality rows
    rhs_source: str = ""        # the constraint that owns that row
    soc: sp.csc_matrix | None = None   # G: rows 3k..3k+2 of G x in the k-th 3-dim second-order cone

    @property
    def n_soc(self) -> int:
        """Number of (3-dimensional) second-order cones."""
        return 0 if self.soc is None else self.soc.shape[0] // 3

    @property
    def n(self) -> int:
        return self.ids.size

    def sizes(self) -> dict:
        return {"variables": int(self.n), "equalities": int(self.A_eq.shape[0]),
                "inequalities": int(self.A_ge.shape[0]),
                "psd_blocks": [int(b) for _, b in self.psd], "second_order_cones": self.n_soc,
                "nnz": int(self.A_eq.nnz + self.A_ge.nnz + (self.soc.nnz if self.soc is not None else 0))}


def positions(ids: np.ndarray, wanted: np.ndarray, what: str = "expression") -> np.ndarray:
    """Positions of decision ids in the program's vector; error if one is foreign."""
    pos = np.searchsorted(ids, wanted)
    pos = np.minimum(pos, max(ids.size - 1, 0))
    if wanted.size and (ids.size == 0 or not np.array_equal(ids[pos], wanted)):
        raise PolynomialError(f"{what} uses decision variables that were not declared in this "
                              "program (made by another SOSProgram?)")
    return pos


def assign_at(p: Polynomial, ids: np.ndarray, x: np.ndarray) -> Polynomial:
    """The decision polynomial p with every decision id replaced by its value in x (ordered as ``ids``)."""
    return p.assign(p.ids, x[positions(ids, p.ids)]) if p.ids.size else p


def objective_value(data: "ConicData", x: np.ndarray) -> float:
    """x^T P x + q^T x + c at x, in the user's sense (maximise -> the maximum)."""
    val = x @ data.q + data.c + (x @ (data.P @ x) if data.P is not None else 0.0)
    return -val if data.sense == "max" else val


def _stack(ids, parts, kind, scale):
    """Rows of one kind stacked: (A, b, largest |b_i| / max_j |A_ij|, its constraint's name).

    ``scale`` divides each row by its largest entry (never for "soc" rows: a cone is not
    invariant under scaling its coordinates separately).
    """
    parts = [p for p in parts if p.kind == kind]
    if not parts:
        return csc(np.zeros(0), np.zeros(0, np.int64), np.zeros(ids.size + 1, np.int64), (0, ids.size)), \
            np.zeros(0), 0.0, ""
    n_rows, r, c, v, rhs, starts = 0, [], [], [], [], []
    for p in parts:
        starts.append(n_rows)
        r.append(p.rows + n_rows)
        c.append(positions(ids, p.ids, f"constraint {p.name!r}"))
        v.append(p.vals)
        rhs.append(p.rhs)
        n_rows += p.rhs.size
    cat = lambda xs: xs[0] if len(xs) == 1 else np.concatenate(xs)  # noqa: E731 -- only read below
    r, c, v, b = cat(r), cat(c), cat(v), np.concatenate(rhs)            # b: a new array, returned
    owner = np.arange(n_rows)
    if kind == "eq":      # 0 = 0 rows carry nothing; 0 = b != 0 rows are caught as infeasible
        keep = (np.bincount(r, minlength=n_rows) > 0) | (b != 0)
        r, b, owner = (np.cumsum(keep) - 1)[r], b[keep], owner[keep]
    if r.size:            # the CSC layout: entries by column, then row; duplicates summed
        order = np.lexsort((r, c))
        r, c, v = r[order], c[order], v[order]
        first = np.flatnonzero(np.concatenate(([True], (r[1:] != r[:-1]) | (c[1:] != c[:-1]))))
        r, c, v = r[first], c[first], np.add.reduceat(v, first)
    norms = np.zeros(b.size)                # largest |A_ij| of each row
    np.maximum.at(norms, r, np.abs(v))
    has = norms > 0
    ratio, source = 0.0, ""
    if has.any():
        rel = np.abs(b[has]) / norms[has]
        worst = int(np.argmax(np.where(np.isnan(rel), np.inf, rel)))
        ratio = float(rel[worst])
        source = parts[int(np.searchsorted(starts, owner[has][worst], side="right")) - 1].name
    if scale and r.size and kind != "soc":
        norms = np.where(has, norms, 1.0)
        v = v * (1.0 / norms)[r]
        b = b / norms
    indptr = np.searchsorted(c, np.arange(ids.size + 1))          # c is sorted (CSC order)
    return csc(v, r, indptr, (b.size, ids.size)), b, ratio, source


def _objective(program, ids):
    if program.objective is None:
        return None, np.zeros(ids.size), 0.0, "min"
    sense, expr = program.objective
    if is_cvxpy(expr):
        return None, np.zeros(ids.size), 0.0, sense
    sign = -1.0 if sense == "max" else 1.0
    q = np.zeros(ids.size)
    if isinstance(expr, QuadraticForm):
        pos = positions(ids, expr.ids, "objective")
        P = sp.coo_matrix(expr.P)
        P = sp.csc_matrix((P.data, (pos[P.row], pos[P.col])), shape=(ids.size, ids.size))
        q[pos] = expr.q
        return P, q, expr.c, sense
    c0, C, expr_ids = affine_rows([expr])
    q[positions(ids, expr_ids, "objective")] = sign * C[0]
    return None, q, sign * c0[0], sense


def assemble(program, scale: bool = True) -> ConicData:
    """Build the :class:`ConicData` of ``program`` (sparse, numeric, no cvxpy)."""
    t0 = time.perf_counter()
    ids = program.ids
    rows = [c.rows for c in program.sos_constraints] + list(program.linear)
    A_eq, b_eq, ratio, source = _stack(ids, rows, "eq", scale)
    A_ge, b_ge, _, _ = _stack(ids, rows, "ge", scale)
    G = _stack(ids, rows, "soc", False)[0]
    psd = [(positions(ids, b.ids), b.size) for b in program.psd_blocks]
    P, q, c, sense = _objective(program, ids)
    reasons = [c.infeasible_reason for c in program.sos_constraints if c.infeasible_reason]
    return ConicData(ids, A_eq, b_eq, A_ge, b_ge, psd, P, q, c, sense, scale,
                     reasons[0] if reasons else None, time.perf_counter() - t0, ratio, source,
                     G if G.shape[0] else None)


def check_data(data: ConicData) -> None:
    """Refuse conic data no solver can resolve in double precision (module docstring)."""
    if not data.rhs_ratio <= MAX_RHS:
        raise InputError(
            f"constraint {data.rhs_source!r} has a coefficient equation whose constant term is "
            f"{data.rhs_ratio:.3g} times its largest decision coefficient (above {MAX_RHS:.0e}): a "
            "solver cannot resolve numbers of such different size in double precision and would "
            "report a wrong status. Try: rescale the variables (x = s*u, so that c*x^k becomes "
            "c*s^k*u^k with moderate c*s^k), or divide the polynomial by its largest coefficient")
    finite = np.isfinite(data.q).all() and np.isfinite(data.c) and (
        data.P is None or np.isfinite(data.P.data).all())
    if not finite:
        raise InputError("the objective has NaN or infinite coefficients. Try: finite numbers in "
                         "the objective")


@dataclass
class AffineCones:
    """PSD blocks imposed on affine expressions instead of on Gram variables.

    A PSD block each of whose svec entries q_i occurs in exactly one equality row r_i, as the
    only entry of such a block in that row, and nowhere else (no inequality, cone or objective
    term) is fixed by its rows: d_i q_i + a_r^T y = b_r gives q = D^-1 (b_R - A_R y) with y the
    other variables. The solver then sees svec^-1(D^-1 (b_R - A_R y)) >= 0 directly: the
    block's variables and rows are gone (for a Gram block of a constant matrix, e.g. the
    learner's ICA step, a third of the KKT system). ``rows[k]`` are the rows fixing block k
    (in svec order) or None; ``keep_rows`` / ``keep_cols`` mark what the solver still sees.
    """

    keep_rows: np.ndarray         # equality rows kept (bool)
    keep_cols: np.ndarray         # variables kept (bool)
    rows: list                    # per PSD block: its fixing equality rows, or None

    def lower(self, data: ConicData):
        """The problem the solver sees, over the kept variables y:

            A_eq y = b_eq (kept rows),  A_ge y >= b_ge,  h - G y in the PSD blocks (in order,
            each svec sized), soc y in the second-order cones,  objective y^T P y + q^T y,

        with h - G y = y[pos] for a kept block and D^-1 (b_R - A_R y) for an eliminated one.
        Returns (A_eq, b_eq, A_ge, G, h, soc, P, q); nothing is copied if nothing is eliminated.
        """
        cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0, dtype=np.int64)  # noqa: E731
        gone = [k for k, rows in enumerate(self.rows) if rows is not None]
        if not gone:                                     # every block on its own variables: G = -E
            c = cat([pos for pos, _ in data.psd])
            G = from_triplets(np.arange(c.size), c, -np.ones(c.size), (c.size, data.n))
            return data.A_eq, data.b_eq, data.A_ge, G, np.zeros(c.size), data.soc, data.P, data.q
        keep, n_keep = self.keep_cols, int(self.keep_cols.sum())
        col = np.cumsum(keep) - 1                        # a kept variable's position among the kept
        sizes = np.array([pos.size for pos, _ in data.psd], dtype=np.int64)
        start = np.concatenate(([0], np.cumsum(sizes)))
        h = np.zeros(start[-1])
        kept = [k for k, r in enumerate(self.rows) if r is None]
        r = cat([start[k] + np.arange(sizes[k]) for k in kept])
        c = col[cat([data.psd[k][0] for k in kept])]
        v = -np.ones(r.size)
        A = data.A_eq.tocsc()
        R = cat([self.rows[k] for k in gone])
        target, d = np.full(A.shape[0], -1), np.ones(A.shape[0])
        target[R] = cat([start[k] + np.arange(sizes[k]) for k in gone])
        d[R] = A.data[A.indptr[cat([data.psd[k][0] for k in gone])]]
        h[target[R]] = data.b_eq[R] / d[R]
        A_col = column_of_entries(A)
        e = ~self.keep_rows[A.indices] & keep[A_col]     # entries of eliminated rows on kept variables
        r = np.concatenate([r, target[A.indices[e]]])
        c = np.concatenate([c, col[A_col[e]]])
        v = np.concatenate([v, A.data[e] / d[A.indices[e]]])
        G = from_triplets(r, c, v, (h.size, n_keep))
        A_eq = _submatrix(A, self.keep_rows, keep)
        P = None if data.P is None else _submatrix(data.P.tocsc(), keep, keep)
        soc = None if data.soc is None else _submatrix(data.soc.tocsc(), None, keep)
        return (A_eq, data.b_eq[self.keep_rows], _submatrix(data.A_ge.tocsc(), None, keep), G, h, soc, P,
                data.q[keep])

    def values(self, data: ConicData, y: np.ndarray, s_blocks: list) -> np.ndarray:
        """The full x from the kept variables y and each eliminated block's cone value s."""
        x = np.zeros(data.n)
        x[self.keep_cols] = y
        for (pos, _), rows, s in zip(data.psd, self.rows, s_blocks):
            if rows is not None:
                x[pos] = s
        return x


def _submatrix(M: sp.csc_matrix, rows, cols) -> sp.csc_matrix:
    """M[rows][:, cols] of a CSC matrix for boolean masks (rows None: all), order kept."""
    M_col = column_of_entries(M)
    on = cols[M_col] if rows is None else cols[M_col] & rows[M.indices]
    new_row = M.indices[on] if rows is None else (np.cumsum(rows) - 1)[M.indices[on]]
    n_cols = int(cols.sum())
    indptr = np.concatenate(([0], np.cumsum(np.bincount((np.cumsum(cols) - 1)[M_col[on]], minlength=n_cols))))
    n_rows = M.shape[0] if rows is None else int(rows.sum())
    return csc(M.data[on], new_row, indptr, (n_rows, n_cols))


def affine_cones(data: ConicData, enabled: bool = True) -> AffineCones:
    """Which PSD blocks of ``data`` are fixed by their equality rows (:class:`AffineCones`);
    none if not ``enabled``."""
    A = data.A_eq.tocsc()
    if not enabled:
        return AffineCones(np.ones(A.shape[0], dtype=bool), np.ones(data.n, dtype=bool), [None] * len(data.psd))
    elsewhere = data.q != 0                           # used outside the equality rows
    for M in (data.A_ge, data.soc, data.P):
        if M is not None:
            elsewhere[np.diff(M.tocsc().indptr) > 0] = True          # columns with entries
    if data.P is not None:
        elsewhere[data.P.tocsc().indices] = True                     # and the rows of P
    once = (np.diff(A.indptr) == 1) & ~elsewhere
    once[once] = A.data[A.indptr[:-1][once]] != 0
    candidate = np.zeros(data.n, dtype=bool)
    for pos, _ in data.psd:
        if pos.size and once[pos].all():
            candidate[pos] = True
    row_of = np.full(data.n, -1)
    row_of[candidate] = A.indices[A.indptr[:-1][candidate]]
    per_row = np.bincount(row_of[candidate], minlength=A.shape[0])
    keep_rows, keep_cols, rows = np.ones(A.shape[0], dtype=bool), np.ones(data.n, dtype=bool), []
    for pos, _ in data.psd:
        r = row_of[pos] if pos.size and candidate[pos].all() else None
        if r is not None and (per_row[r] == 1).all():
            keep_rows[r], keep_cols[pos] = False, False
            rows.append(r)
        else:
            rows.append(None)
    return AffineCones(keep_rows, keep_cols, rows)


def cvxpy_block_vars(program) -> list:
    """One cvxpy Variable per declared block (created once, reused by every solve)."""
    import cvxpy as cp              # lazily (3 s to import): see the module docstring
    out = []
    for b in program.blocks:
        key = int(b.ids[0]) if b.ids.size else id(b)
        if key not in program.cvxpy_vars:
            program.cvxpy_vars[key] = cp.Variable(b.ids.size, name=b.name)
        out.append(program.cvxpy_vars[key])
    return out


def cvxpy_affine(program, item):
    """cvxpy expression c0 + C x[pos] of degree-0 affine polynomial(s) of ``program``."""
    import cvxpy as cp              # lazily (3 s to import): see the module docstring
    if isinstance(item, PolyMatrix):
        rows = [[cvxpy_affine(program, p) for p in row] for row in item.entries]
        return cp.bmat(rows)
    if not isinstance(item, Polynomial):
        raise InputError(f"expr() takes a Polynomial or PolyMatrix, got {type(item).__name__}")
    c0, C, item_ids = affine_rows([item])
    if not item_ids.size:
        return cp.Constant(c0[0])
    x = cp.hstack(cvxpy_block_vars(program))
    pos = positions(program.ids, item_ids, "expression")
    return c0[0] + C[0] @ x[pos]

"""Exact certificates on the face the solver's kernel names (facial reduction, then Peyrl-Parrilo).

Some certificates have no floating-point margin on any face of coordinates: every Gram matrix
of Beale's function is singular along (0, 1, 1, 1, 1) in the basis (1, x, xy, xy^2, xy^3)
(its x^2-part vanishes at y = 1, a zero at infinity) and along z(3, 1/2) (its zero); every Gram
matrix of the SOS matrix [[1 + x^2, x y^2], [x y^2, 1 + y^4]] = v v^T + I along
y_0 x - y_1 y^2; the last clique of the chained Rosenbrock function along x_n - x_(n-1)^2. The
solver's Gram matrix Q shows these directions as its (numerical) kernel. Here each block's
kernel is read in rational numbers: the reduced echelon form of its eigenvectors of eigenvalue
below ``tol`` x the largest (tol in KERNEL_TOLS), by complete pivoting -- each pivot the largest
entry left, so the solver's noise is never divided by a small one -- with entries rounded to
small denominators, at most ROUNDING from the floats (an interior-point solver approaches its
face only to about the square root of its tolerance); and the block restricted to the face Q = U R U^T, U a rational basis of the kernel's orthogonal
complement (Permenter & Parrilo's facial reduction with the solver's kernel as the certificate
candidate). The coefficient matching over the R's and the free decisions is then solved exactly:
an exact rational correction of the solver's numbers rounded to a grid (GRID), on unknowns
chosen in floating point (:func:`exact_solution`) (Peyrl & Parrilo 2008, *Computing
sum of squares decompositions with rational coefficients*), and every R proven PSD
(:func:`~.gram.proven_min_eig`). On the right face R has a margin (for v v^T + I the identity),
and the objective is whatever the exact system makes it (Beale's bound is exactly 0).

A kernel that is not the face's (a rounding of an irrational zero, a direction of one solver's
point only) makes the system inconsistent or R indefinite: nothing is claimed. Only for programs
of at most MAX_ROWS coefficient equations (rational elimination is cubic in them).
"""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from ..errors import UnverifiedSolutionError
from ..poly import Polynomial
from .conic import positions
from .gram import SQRT2, exact, exact_solution, float_down, proven_min_eig, svec_pairs, svec_to_matrix
from .objective import affine_rows
from .identity import identity_of
from .rigorous import Bound, _exps_in, constraint_map

KERNEL_TOLS = (1e-9, 1e-7, 1e-5)   # eigenvalues below this x the block's largest are its kernel, tried in turn
DENOMINATOR = 1000       # largest denominator of a kernel vector's entries
ROUNDING = 1e-3          # how far the floats' echelon form may be from its rounding (an interior-point
#                          solver's face is known to about the square root of its tolerance)
MAX_ROWS = 400           # coefficient equations up to which the exact system is solved
SPAN_TOL = 1e-2         # singular values of the kernel's span below this are the solver's noise
GRID = 2.0**-40          # the solver's numbers are rounded to this grid (relative) first: short rationals


def on_grid(v: float, step: float) -> Fraction:
    """v rounded to a multiple of the power of two at most ``step`` (v itself when step is 0)."""
    if step <= 0 or not np.isfinite(step):
        return Fraction(v)
    h = Fraction(2) ** (math.frexp(step)[1] - 1)
    return round(Fraction(v) / h) * h


def rational_face(Q, keep_row=None, tol=1e-7, zero_rows=()):
    """U (n x r, Fractions; columns span the orthogonal complement of Q's rational kernel), or
    None when the kernel has no rational echelon form. ``keep_row``: the kernel is restricted to
    vectors vanishing there (the constant monomial of a bound, which lowering gamma reaches);
    ``zero_rows``: coordinate vectors added to it (rows the polynomial does not need, :mod:`.proof`)."""
    n = Q.shape[0]
    w, V = np.linalg.eigh(Q)
    top = max(float(w.max(initial=0.0)), 0.0)
    K = V[:, w <= tol * top] if top > 0 else V
    if len(zero_rows):              # an orthonormal basis of K and the rows: one K holds already
        u, s, _ = np.linalg.svd(np.hstack([K, np.eye(n)[:, list(zero_rows)]]), full_matrices=False)
        K = u[:, s > SPAN_TOL]      # (to the solver's accuracy) adds no direction
    if keep_row is not None and K.shape[1]:
        _, s, vt = np.linalg.svd(K[keep_row:keep_row + 1, :])
        rank = int((s > 1e-9).sum())
        K = K @ vt[rank:].T
    if not K.shape[1]:
        return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    R = K.T.copy()                              # its reduced echelon form, complete pivoting
    pivots = []
    for row in range(R.shape[0]):
        rest = np.abs(R[row:]).copy()
        rest[:, pivots] = 0.0
        k, col = np.unravel_index(int(np.argmax(rest)), rest.shape)
        k += row
        R[[row, k]] = R[[k, row]]
        R[row] /= R[row, col]
        others = np.arange(R.shape[0]) != row
        R[others] -= np.outer(R[others, col], R[row])
        pivots.append(int(col))
    E = [[Fraction(float(v)).limit_denominator(DENOMINATOR) for v in r] for r in R]
    if max(abs(float(e) - v) for r, fr in zip(R, E) for e, v in zip(fr, r)) > ROUNDING:
        return None
    free = [c for c in range(n) if c not in pivots]
    U = [[Fraction(0)] * len(free) for _ in range(n)]
    for a, f in enumerate(free):
        U[f][a] = Fraction(1)
        for r, p in enumerate(pivots):
            U[p][a] = -E[r][f]
    return U


def _face_terms(U, size):
    """Q_ij for i <= j as {R unknown (a, c), a <= c: exact coefficient}, Q = U R U^T."""
    r = len(U[0]) if U else 0
    out = {}
    for i, j in zip(*svec_pairs(size)):
        terms = {}
        for a in range(r):
            for c in range(a, r):
                v = U[i][a] * U[j][c] + (U[i][c] * U[j][a] if a != c else 0)
                if v:
                    terms[(a, c)] = v
        out[(int(i), int(j))] = terms
    return out


def kernel_bound(program, data, x, keep_constant: bool, tol: float = 1e-7, zero_squares: bool = False) -> Bound:
    """The exact certificate of the module docstring near x (ordered as ``data.ids``); a Bound
    (``proven`` None for a program without objective), or UnverifiedSolutionError. ``zero_squares``:
    the rows of a constraint's Gram block whose square no other term of its identity reaches (its
    coefficient in the polynomial is 0: the diagonal rule of facial reduction) join the kernel."""
    sense, expr = program.objective or (None, None)
    if program.cvxpy_constraints or (sense is not None and not isinstance(expr, Polynomial)):
        raise UnverifiedSolutionError("only affine objectives and no cvxpy constraints have an exact form",
                                      "unverified")
    equations = sum(identity_of(con).n_mon for con in program.sos_constraints)
    if equations > MAX_ROWS:
        raise UnverifiedSolutionError(f"{equations} coefficient equations, above {MAX_ROWS}", "unverified")
    at = lambda ids: x[positions(data.ids, ids)]  # noqa: E731
    half = exact(SQRT2) / 2
    zeros = {}
    for con in program.sos_constraints:
        ident = identity_of(con)
        for k, (basis, psd) in enumerate(con.gram_blocks):
            i, j = svec_pairs(psd.size)
            zeros[id(psd)] = np.flatnonzero(ident.other_terms[ident.pair_mon[k][i == j]] == 0)
    start, entry = {}, {}
    faces = []
    for b in program.blocks:
        if b.psd is None or not b.psd.size:
            continue
        Q = svec_to_matrix(at(b.ids), b.psd.size)
        keep = None
        if keep_constant and b.psd.role in ("gram", "clique"):
            keep = next((k for con in program.sos_constraints for basis, psd in con.gram_blocks if psd is b.psd
                         for k in np.flatnonzero(~basis.exps.any(axis=1))[:1]), None)
        U = rational_face(Q, keep, tol, zeros.get(id(b.psd), ()) if zero_squares else ())
        if U is None:
            raise UnverifiedSolutionError(f"block {b.name!r}: its kernel has no small rational form", "unverified")
        Uf = np.array([[float(v) for v in row] for row in U]) if U and U[0] else np.zeros((Q.shape[0], 0))
        pinv = np.linalg.pinv(Uf) if Uf.size else Uf.T
        R0 = pinv @ Q @ pinv.T
        faces.append((b, U))
        for (i, j), terms in _face_terms(U, b.psd.size).items():
            k = j * (j + 1) // 2 + i
            scale = Fraction(1) if i == j else 1 / half          # s_k = Q_ij / (sqrt2 / 2) off the diagonal
            entry[int(b.ids[k])] = {("R", id(b.psd), a, c): v * scale for (a, c), v in terms.items()}
        grid = GRID * float(np.abs(R0).max(initial=0.0))
        for a in range(R0.shape[0]):
            for c in range(a, R0.shape[0]):
                start[("R", id(b.psd), a, c)] = on_grid(float(R0[a, c]), grid)
    for d in (int(d) for b in program.blocks if b.psd is None for d in b.ids):
        v = float(at(np.array([d]))[0])
        start[d] = on_grid(v, GRID * abs(v))

    def substitute(lin):
        out = {}
        for d, v in lin.items():
            for u, w in (entry[d].items() if d in entry else ((d, 1),)):
                out[u] = out.get(u, 0) + v * w
        return out
    rows = []
    for con in program.sos_constraints:
        amap = constraint_map(con)
        B = _exps_in(con.basis, con.basis.vars)
        for i, j in zip(*svec_pairs(len(con.basis))):
            m = tuple(int(v) for v in B[i] + B[j])
            k = int(con.psd.ids[j * (j + 1) // 2 + i])
            merge = amap.setdefault(m, [Fraction(0), {}])
            merge[1][k] = merge[1].get(k, 0) - (1 if i == j else 2 * half)   # minus z^T Q z, Q_ij = s_k sqrt2/2
        rows += [(c, substitute(lin)) for c, lin in amap.values()]
    for lin_rows in (r for r in program.linear if r.role == "user" and r.kind == "eq"):
        eqs = [[-exact(v), {}] for v in lin_rows.rhs]
        for r, d, v in zip(lin_rows.rows, lin_rows.ids, lin_rows.vals):
            eqs[r][1][int(d)] = eqs[r][1].get(int(d), 0) + exact(v)
        rows += [(c, substitute(lin)) for c, lin in eqs]
    rows = [(c, lin) for c, lin in rows if c or lin]
    if len(rows) > MAX_ROWS:
        raise UnverifiedSolutionError(f"{len(rows)} coefficient equations, above {MAX_ROWS}", "unverified")
    avoid = [] if sense is None else [int(d) for d in affine_rows([expr])[2]]
    delta = exact_solution(rows, start, avoid)
    if delta is None:
        raise UnverifiedSolutionError("the coefficient equations are inconsistent on the kernel's face", "unverified")
    values = {k: v + delta.get(k, 0) for k, v in start.items()}
    margins = {}
    for b, U in faces:
        r = len(U[0]) if U else 0
        R = np.empty((r, r), dtype=object)
        for a in range(r):
            for c in range(a, r):
                R[a, c] = R[c, a] = values[("R", id(b.psd), a, c)]
        lb = proven_min_eig(R)
        if lb is None:
            raise UnverifiedSolutionError(f"block {b.name!r} is not provably PSD on the kernel's face", "unverified")
        margins[b.name] = lb
    def exact_value(d):
        return sum((values[u] * w for u, w in entry[d].items()), Fraction(0)) if d in entry else values[d]
    for lin_rows in (r for r in program.linear if r.role == "user" and r.kind == "ge"):
        lhs = [-exact(v) for v in lin_rows.rhs]
        for r, d, v in zip(lin_rows.rows, lin_rows.ids, lin_rows.vals):
            lhs[r] += exact(v) * exact_value(int(d))
        if any(v < 0 for v in lhs):
            raise UnverifiedSolutionError(f"inequality {lin_rows.name!r} fails at the exact point", "unverified")
    point = np.array([float(exact_value(int(d))) for d in data.ids])
    if sense is None:
        return Bound(None, None, None, "kernel face", point, margins)
    c0, C, ids = affine_rows([expr])
    value = exact(c0[0]) + sum((exact(c) * exact_value(int(d)) for c, d in zip(C[0], ids)), Fraction(0))
    proven = float_down(value) if sense == "max" else -float_down(-value)
    solver = float(c0[0] + C[0] @ x[positions(data.ids, ids)])
    return Bound(sense, solver, proven, "kernel face", point, margins)

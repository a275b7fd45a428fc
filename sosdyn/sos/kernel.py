"""Exact certificates on the face the solver's kernel names (facial reduction, then Peyrl-Parrilo).

Some certificates have no floating-point margin on any face of coordinates: every Gram matrix
of Beale's function is singular along (0, 1, 1, 1, 1) in the basis (1, x, xy, xy^2, xy^3)
(its x^2-part vanishes at y = 1, a zero at infinity) and along z(3, 1/2) (its zero); every Gram
matrix of the SOS matrix [[1 + x^2, x y^2], [x y^2, 1 + y^4]] = v v^T + I along
y_0 x - y_1 y^2; the last clique of the chained Rosenbrock function along x_n - x_(n-1)^2; its
dense Gram matrices along z(1), x_n + x_(n-1)^2 and the rows x_(n-1) x_j, j < n - 1 (along
x_(n-2) = t^(1/2), x_(n-1) = t, x_n = t^2 the function grows like t^2, so no square may hold
x_(n-1) x_j). The solver's Gram matrix Q shows these directions as its (numerical) kernel. Here
each block's kernel is read in rational numbers: the reduced echelon form of its eigenvectors of
eigenvalue below ``tol`` x the largest (tol in KERNEL_TOLS), by complete pivoting -- each pivot
the largest entry left, so the solver's noise is never divided by a small one -- with entries
rounded to small denominators (ROUNDINGS: integers within 0.1 first, then denominators up to
1000 within 1e-3; an interior-point solver approaches its face only to about the square root of
its tolerance, and on the ill-conditioned face of dense chained Rosenbrock the echelon entries
were off by up to 4e-2); and the block restricted to the face Q = U R U^T, U a rational basis
of the kernel's orthogonal complement (Permenter & Parrilo's facial reduction with the solver's
kernel as the certificate candidate). On the face the program has an interior, so it is solved
again there, in floating point (:func:`face_solve`; the first answer, on a program without one,
is too far from the face: dense chained Rosenbrock n = 6's, projected onto its face, missed the
coefficient equations by 1e-2 against R's smallest eigenvalue 1e-3). The coefficient matching
over the R's and the free decisions is then solved exactly: an exact rational correction of the
re-solved numbers (else the solver's) rounded to a grid (GRID), on unknowns chosen in floating
point (:func:`exact_solution`) (Peyrl & Parrilo 2008, *Computing sum of squares decompositions
with rational coefficients*), and every R proven PSD (:func:`~.gram.proven_min_eig`). On the
right face R has a margin (for v v^T + I the identity; dense chained Rosenbrock n = 6, 8, 10:
0.10, 0.067, 0.053 against a largest 200), and the objective is whatever the exact system makes
it (Beale's and chained Rosenbrock's bound are exactly 0).

A kernel that is not the face's (a rounding of an irrational zero, a direction of one solver's
point only) makes the system inconsistent or R indefinite: nothing is claimed. Any U gives a
restriction Q = U R U^T, R >= 0, of the program, so what is proven is a certificate whatever
the face. Only for programs of at most MAX_ROWS coefficient equations (rational elimination is
cubic in them).
"""
from __future__ import annotations

import math
from fractions import Fraction

import clarabel
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import UnverifiedSolutionError
from ..poly import Polynomial
from .conic import positions
from .gram import SQRT2, exact, exact_solution, float_down, proven_min_eig, svec_pairs, svec_to_matrix
from .objective import affine_rows
from .identity import identity_of
from .native import INTERRUPTS, native_stderr
from .rigorous import Bound, _exps_in, constraint_map

KERNEL_TOLS = (1e-9, 1e-7, 1e-5)   # eigenvalues below this x the block's largest are its kernel, tried in turn
#: (largest denominator of a kernel vector's entries, how far the floats' echelon form may be from
#: its rounding), tried in turn: an interior-point solver's face is known to about the square root
#: of its tolerance, worse on an ill-conditioned face (dense chained Rosenbrock: 4e-2), where only
#: integers are far enough apart to be read
ROUNDINGS = ((1, 0.1), (1000, 1e-3))
MAX_ROWS = 2500          # coefficient equations up to which the exact system is solved (dense chained
#                         Rosenbrock n = 11, 12, 14: 1068, 1444, 2486 equations, 0 exactly in 15, 35, 132 s)
SPAN_TOL = 1e-2         # singular values of the kernel's span below this are the solver's noise
GRID = 2.0**-40          # the solver's numbers are rounded to this grid (relative) first: short rationals


def on_grid(v: float, step: float) -> Fraction:
    """v rounded to a multiple of the power of two at most ``step`` (v itself when step is 0)."""
    if step <= 0 or not np.isfinite(step):
        return Fraction(v)
    h = Fraction(2) ** (math.frexp(step)[1] - 1)
    return round(Fraction(v) / h) * h


def rational_face(Q, keep_row=None, tol=1e-7, zero_rows=(), rounding=ROUNDINGS[-1]):
    """U (n x r, Fractions; columns span the orthogonal complement of Q's rational kernel), or
    None when the kernel has no rational echelon form. ``keep_row``: the kernel is restricted to
    vectors vanishing there (the constant monomial of a bound, which lowering gamma reaches);
    ``zero_rows``: coordinate vectors added to it (rows the polynomial does not need, :mod:`.proof`);
    ``rounding``: (largest denominator, largest distance of an entry from it) (ROUNDINGS)."""
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
    denominator, distance = rounding
    E = [[Fraction(float(v)).limit_denominator(denominator) for v in r] for r in R]
    if max(abs(float(e) - v) for r, fr in zip(R, E) for e, v in zip(fr, r)) > distance:
        return None
    free = [c for c in range(n) if c not in pivots]
    U = [[Fraction(0)] * len(free) for _ in range(n)]
    for a, f in enumerate(free):
        U[f][a] = Fraction(1)
        for r, p in enumerate(pivots):
            U[p][a] = -E[r][f]
    return U


def _face_terms(U, size):
    """Q_ij for i <= j as {R unknown (a, c), a <= c: exact coefficient}, Q = U R U^T (over the
    nonzeros of U's rows: most are one coordinate)."""
    nonzero = [[(a, v) for a, v in enumerate(row) if v] for row in U]
    out = {}
    for i, j in zip(*svec_pairs(size)):
        terms = {}
        for a, u in nonzero[i]:
            for c, w in nonzero[j]:
                key = (a, c) if a <= c else (c, a)
                terms[key] = terms.get(key, 0) + u * w
        out[(int(i), int(j))] = {k: v for k, v in terms.items() if v}
    return out


def face_solve(rows, ge_rows, faces, start, gain) -> dict | None:
    """The program again on the faces, in floating point: every coefficient equation in ``rows``
    (an independent subset) and ``ge_rows`` (c + sum a u >= 0) over the free decisions and the
    R of each face (``faces``, each R >= 0), ``gain`` ({unknown: coefficient}) maximised, by
    Clarabel. On the face of every certificate the reduced program has an interior, so its answer
    is accurate where the first, on a program without one, was not (the re-solve of Permenter &
    Parrilo's facial reduction). The unknowns as ``start`` has them, on the grid; None without an
    answer."""
    free = sorted(u for u in start if not isinstance(u, tuple))
    col = {u: k for k, u in enumerate(free)}
    sizes = []
    for b, U in faces:
        r = len(U[0]) if U else 0
        for a, c in zip(*svec_pairs(r)):
            col[("R", id(b.psd), int(a), int(c))] = len(col)
        sizes.append(r)
    scale = {u: 1.0 if not isinstance(u, tuple) or u[2] == u[3] else 1 / SQRT2 for u in col}   # R_ac = s / sqrt2

    def matrix(lines):
        A = np.zeros((len(lines), len(col)))
        for i, (_, lin) in enumerate(lines):
            for u, a in lin.items():
                A[i, col[u]] += float(a) * scale[u]
        return A, np.array([-float(c) for c, _ in lines])
    A, b = matrix(rows)
    if A.size:
        _, Rr, order = sla.qr(A.T, mode="economic", pivoting=True)
        d = np.abs(np.diag(Rr))
        use = np.sort(order[:int((d > 1e-10 * d.max(initial=0.0)).sum())])
        A, b = A[use], b[use]
    G, h = matrix(ge_rows)
    psd = np.zeros((sum(r * (r + 1) // 2 for r in sizes), len(col)))
    psd[:, len(free):] = -np.eye(psd.shape[0])                     # s = svec(R) in the PSD cones
    q = np.zeros(len(col))
    for u, c in gain.items():
        q[col[u]] -= float(c) * scale[u]
    cones = ([clarabel.ZeroConeT(A.shape[0])] if A.shape[0] else []) + \
        ([clarabel.NonnegativeConeT(G.shape[0])] if G.shape[0] else []) + [clarabel.PSDTriangleConeT(r) for r in sizes if r]
    opts = clarabel.DefaultSettings()
    opts.verbose = False
    with native_stderr():
        try:
            result = clarabel.DefaultSolver(sp.csc_matrix((len(col), len(col))), q, sp.csc_matrix(np.vstack([A, -G, psd])),
                                            np.concatenate([b, -h, np.zeros(psd.shape[0])]), cones, opts).solve()
        except BaseException as exc:      # a Rust panic (no answer, like a failed solve)
            if isinstance(exc, INTERRUPTS):
                raise
            return None
    if str(result.status) not in ("Solved", "AlmostSolved") or not np.isfinite(result.x).all():
        return None
    y = np.array([result.x[col[u]] * scale[u] for u in start])
    top = {}
    for u, v in zip(start, y):
        if isinstance(u, tuple):
            top[u[1]] = max(top.get(u[1], 0.0), abs(v))
    return {u: on_grid(v, GRID * (top[u[1]] if isinstance(u, tuple) else abs(v))) for u, v in zip(start, y)}


def kernel_bound(program, data, x, keep_constant: bool, tol: float = 1e-7, zero_squares: bool = False,
                 rounding=ROUNDINGS[-1]) -> Bound:
    """The exact certificate of the module docstring near x (ordered as ``data.ids``); a Bound
    (``proven`` None for a program without objective), or UnverifiedSolutionError. ``zero_squares``:
    the rows of a constraint's Gram block whose square no other term of its identity reaches (its
    coefficient in the polynomial is 0: the diagonal rule of facial reduction) join the kernel;
    ``rounding``: how the kernel is read (:func:`rational_face`). The exact correction starts from
    the program solved again on the faces (:func:`face_solve`), else from x on them."""
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
        U = rational_face(Q, keep, tol, zeros.get(id(b.psd), ()) if zero_squares else (), rounding)
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
    ge_rows, ge_names = [], []
    for lin_rows in (r for r in program.linear if r.role == "user" and r.kind == "ge"):
        ges = [[-exact(v), {}] for v in lin_rows.rhs]
        for r, d, v in zip(lin_rows.rows, lin_rows.ids, lin_rows.vals):
            ges[r][1][int(d)] = ges[r][1].get(int(d), 0) + exact(v)
        ge_rows += [(c, substitute(lin)) for c, lin in ges]
        ge_names += [lin_rows.name] * len(ges)
    c0, C, ids = affine_rows([expr]) if sense is not None else (None, np.zeros((1, 0)), [])
    gain = substitute({int(d): exact(c) * (1 if sense == "max" else -1) for c, d in zip(C[0], ids)})
    start = face_solve(rows, ge_rows, faces, start, gain) or start
    avoid = [int(d) for d in ids]
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
    for (c, lin), name in zip(ge_rows, ge_names):
        if c + sum((a * values[u] for u, a in lin.items()), Fraction(0)) < 0:
            raise UnverifiedSolutionError(f"inequality {name!r} fails at the exact point", "unverified")
    point = np.array([float(exact_value(int(d))) for d in data.ids])
    if sense is None:
        return Bound(None, None, None, "kernel face", point, margins)
    value = exact(c0[0]) + sum((exact(c) * exact_value(int(d)) for c, d in zip(C[0], ids)), Fraction(0))
    proven = float_down(value) if sense == "max" else -float_down(-value)
    solver = float(c0[0] + C[0] @ x[positions(data.ids, ids)])
    return Bound(sense, solver, proven, "kernel face", point, margins)

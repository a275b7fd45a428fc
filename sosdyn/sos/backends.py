"""Solver back ends: the boundary between sosdyn's conic data and a conic solver.

* ``direct``: Clarabel's own API on :class:`~.conic.ConicData` (no canonicalisation, so a
  re-solve with new numbers costs only the solve);
* ``cvxpy``: the same data as a cvxpy problem (any installed cvxpy solver, plus user
  cvxpy constraints and objectives).

Both return a :class:`~.solution.Solution` with a normalised status:
"optimal" | "optimal_inaccurate" | "infeasible" | "unbounded" | "solver_error".

Both also hand the dual of every PSD block to the Solution (``info["psd_duals"]``: Clarabel's z
on the PSD cones, or the cvxpy PSD constraints' ``dual_value``), from which
:mod:`.moments` reads moment matrices. Through cvxpy each block is one constraint
``svec^-1(x[block]) >> 0`` on the expression itself: no extra matrix variable tied to x by
equalities, whose n^2 rows repeat each off-diagonal entry (cvxpy stores a symmetric variable
once) and made CVXOPT stop with "Rank(A) < p".

Before anything reaches a solver, the data is checked (:func:`~.conic.check_data`) and the
solver's working memory is estimated (:func:`solver_bytes`) and compared with
``sosdyn.limits`` (max_bytes): over it, :class:`~sosdyn.errors.ResourceLimitError`.
"""
from __future__ import annotations

import sys
import time

import clarabel
import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..limits import check_bytes, get_limits
from ..poly import MAX_COEFFICIENT
from .conic import affine_cones, check_data, cvxpy_block_vars
from .csc import csc, vstack
from .gram import svec_pairs, svec_to_matrix
from .kkt import factor_entries
from .native import INTERRUPTS, native_stderr
from .objective import is_cvxpy
from .solution import Solution

SOLVERS = ("CLARABEL", "SCS")    # the solvers sosdyn is tested with; any installed cvxpy solver works

_CLARABEL_STATUS = {
    "Solved": "optimal", "AlmostSolved": "optimal_inaccurate",
    "PrimalInfeasible": "infeasible", "AlmostPrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded", "AlmostDualInfeasible": "unbounded",
}
# The memory model of a solve (bytes; see solver_bytes), calibrated on the peak RSS of dense
# SOS programs with Clarabel 0.11, SCS 3 and cvxpy 1.9 (measured 38-46 bytes per entry of a
# single dense group D x D, 23 with coupled multiplier blocks; 160-210 per nonzero of an LP).
DENSE_BYTES = 56                 # per entry of a D x D dense group: 2 x 56 per factor entry (kkt)
SPARSE_BYTES = 400               # per nonzero, row and column of the sparse KKT part
BASE_BYTES = 16 * 2**20          # the solver's fixed cost
CVXPY_BASE_BYTES = 96 * 2**20    # importing cvxpy and canonicalising
CVXPY_ENTRY_BYTES = 2048         # per nonzero of A and per entry of a b x b PSD matrix variable
SCS_CONE_BYTES = 32              # per entry of a b x b PSD block (SCS's eigendecompositions)

_CVXPY_STATUS = {
    "optimal": "optimal", "optimal_inaccurate": "optimal_inaccurate",
    "infeasible": "infeasible", "infeasible_inaccurate": "infeasible",
    "unbounded": "unbounded", "unbounded_inaccurate": "unbounded",
}


def _clarabel(data, verbose, settings):
    """Solve ``data`` with Clarabel: A x + s = b, s in (zero, nonnegative, PSD, SOC) cones.

    ``settings`` are Clarabel's, except sosdyn's own ``affine_psd``: if true, PSD blocks fixed
    by their equality rows (:func:`~.conic.affine_cones`) are imposed on their affine
    expressions; their entries are read back from the cone's s, so x is still the full vector
    of the program and the independent check sees every block and every row. The answer is the
    same problem's to the solver's tolerance, not bit for bit (another KKT system), hence
    opt-in."""
    settings = dict(settings)
    red = affine_cones(data, enabled=settings.pop("affine_psd", False))
    P, q, A, b, cones = clarabel_problem(data, red)
    opts = clarabel.DefaultSettings()
    opts.verbose = verbose
    for k, v in settings.items():
        if not hasattr(opts, k):
            raise InputError(f"unknown Clarabel setting {k!r}")
        setattr(opts, k, v)
    t0 = time.perf_counter()
    result = clarabel.DefaultSolver(P, q, A, b, cones, opts).solve()
    seconds = time.perf_counter() - t0
    status = _CLARABEL_STATUS.get(str(result.status), "solver_error")
    z, s = np.asarray(result.z, dtype=float), np.asarray(result.s, dtype=float)
    start = int(red.keep_rows.sum()) + data.b_ge.size           # rows before the PSD parts
    duals, s_blocks = [], []
    for pos, size in data.psd:          # z's PSD parts: svec of each block's dual matrix
        duals.append(svec_to_matrix(z[start:start + pos.size], size))
        s_blocks.append(s[start:start + pos.size])
        start += pos.size
    x = red.values(data, np.asarray(result.x, dtype=float), s_blocks)
    return status, x, str(result.status), seconds, {"iterations": int(result.iterations), "psd_duals": duals,
                                                    "solver_own_seconds": float(result.solve_time)}


def clarabel_problem(data, red):
    """Clarabel's (P, q, A, b, cones) of ``data`` lowered by ``red`` (:class:`~.conic.AffineCones`):
    rows A_eq (zero cone), A_ge (nonnegative), the PSD blocks, the second-order cones."""
    A_eq, b_eq, A_ge, G, h, soc, P, q = red.lower(data)
    blocks, rhs, cones = [(A_eq.tocsc(), 1), (A_ge.tocsc(), -1)], [b_eq, -data.b_ge], []
    if A_eq.shape[0]:
        cones.append(clarabel.ZeroConeT(A_eq.shape[0]))
    if A_ge.shape[0]:
        cones.append(clarabel.NonnegativeConeT(A_ge.shape[0]))
    blocks.append((G, 1))                   # s = h - G y in each PSD block
    rhs.append(h)
    cones += [clarabel.PSDTriangleConeT(size) for _, size in data.psd]
    if data.n_soc:                          # s = G x in each 3-dim second-order cone
        blocks.append((soc.tocsc(), -1))
        rhs.append(np.zeros(soc.shape[0]))
        cones += [clarabel.SecondOrderConeT(3)] * data.n_soc
    A = vstack(blocks, q.size)
    P = sp.triu(2.0 * P).tocsc() if P is not None else csc(np.zeros(0), np.zeros(0, dtype=np.int64),
                                                           np.zeros(q.size + 1, dtype=np.int64), (q.size, q.size))
    return P, q, A, np.concatenate(rhs), cones


def _svec_to_vec_map(size):
    """Sparse map from svec (scaled) to the column-major vec of the symmetric matrix."""
    i, j = svec_pairs(size)
    w = np.where(i == j, 1.0, 1.0 / np.sqrt(2.0))
    rows = np.concatenate([i + size * j, j + size * i])
    cols = np.concatenate([np.arange(i.size)] * 2)
    vals = np.concatenate([w, np.where(i == j, 0.0, w)])
    return sp.csr_matrix((vals, (rows, cols)), shape=(size * size, i.size))


def _cvxpy(program, data, solver, verbose, settings):
    import cvxpy as cp              # lazily: about 3 s to import, only this back end needs it

    x = cp.hstack(cvxpy_block_vars(program))
    cons = []
    if data.A_eq.shape[0]:
        cons.append(data.A_eq @ x == data.b_eq)
    if data.A_ge.shape[0]:
        cons.append(data.A_ge @ x >= data.b_ge)
    psd_cons = []
    for pos, size in data.psd:      # Q = svec^-1(x[pos]) >> 0 itself: no equality rows Q = svec^-1(x)
        Q = cp.reshape(_svec_to_vec_map(size) @ x[pos], (size, size), order="F")
        psd_cons.append(Q >> 0)
    cons += psd_cons
    if data.n_soc:
        s = cp.reshape(data.soc @ x, (3, data.n_soc), order="F")
        cons.append(cp.SOC(s[0], s[1:], axis=0))
    cons += program.cvxpy_constraints
    expr = program.objective[1] if program.objective else None
    if isinstance(expr, cp.Expression):
        obj = cp.Minimize(expr) if program.objective[0] == "min" else cp.Maximize(expr)
    else:
        f = data.q @ x + data.c
        if data.P is not None:
            f = f + cp.quad_form(x, cp.psd_wrap(data.P))
        obj = cp.Minimize(f)
    problem = cp.Problem(obj, cons)
    t0 = time.perf_counter()
    try:
        problem.solve(solver=solver, verbose=verbose, **settings)
        raw = problem.status
    except cp.error.SolverError as exc:
        raw = f"solver_error: {exc}"
    seconds = time.perf_counter() - t0
    status = _CVXPY_STATUS.get(raw, "solver_error")
    value = x.value if x.value is not None else np.full(data.n, np.nan)
    stats = problem.solver_stats
    info = {"compile_seconds": getattr(problem, "compilation_time", None) or 0.0,
            "solver_seconds": getattr(stats, "solve_time", None) if stats else None,
            "iterations": getattr(stats, "num_iters", None) if stats else None}
    if program.objective and isinstance(program.objective[1], cp.Expression):
        info["objective"] = problem.value
    if all(c.dual_value is not None for c in psd_cons):
        info["psd_duals"] = [np.asarray(c.dual_value, dtype=float) for c in psd_cons]
    return status, np.asarray(value, dtype=float), raw, seconds, info


def solver_bytes(data, solver: str, backend: str) -> float:
    """A conservative estimate of the working memory (bytes) of solving ``data``.

    An interior-point solver (Clarabel, and every cvxpy solver but SCS) factors a KKT matrix
    in which each PSD cone of svec size s is a dense s x s block; F, the entries of its
    factor (:func:`~.kkt.factor_entries`: each block dense, then its rows eliminated in
    minimum-degree order), follows the sparsity of the program: one dense group of D columns
    and rows gives D^2 / 2, a chain of small clique blocks a sum of small terms. With nnz the
    nonzeros of A (plus one per svec entry for the cone rows, plus P), N the rows and columns
    of the KKT matrix,

        bytes = BASE + SPARSE (nnz + N) + 2 DENSE F
                [+ CVXPY_BASE + CVXPY_ENTRY (nnz(A) + sum_k b_k^2) through cvxpy].

    SCS (first order, through cvxpy) never forms the dense blocks: its factor term is replaced
    by SCS_CONE sum_k b_k^2 (eigendecompositions of the b x b blocks).
    """
    b = np.array([size for _, size in data.psd], dtype=float)
    s = b * (b + 1) / 2
    nnz_a = data.A_eq.nnz + data.A_ge.nnz + (data.soc.nnz if data.soc is not None else 0)
    nnz = nnz_a + s.sum() + (data.P.nnz if data.P is not None else 0)
    dim = data.n + data.A_eq.shape[0] + data.A_ge.shape[0] + 3 * data.n_soc + s.sum()
    total = BASE_BYTES + SPARSE_BYTES * (nnz + dim)
    if solver == "SCS":
        total += SCS_CONE_BYTES * (b**2).sum()
    else:
        total += 2 * DENSE_BYTES * factor_entries(data)
    if backend == "cvxpy":
        total += CVXPY_BASE_BYTES + CVXPY_ENTRY_BYTES * (nnz_a + (b**2).sum())
    return float(total)


def coarse_bytes(data) -> float:
    """An upper bound of :func:`solver_bytes` for Clarabel through the direct back end, from
    sizes alone: one dense group of every variable and row (D = n + rows, F <= D (D + 1) / 2),
    each svec entry counted as a variable (so the bound needs no pass over the PSD blocks)."""
    rows = data.A_eq.shape[0] + data.A_ge.shape[0] + 3 * data.n_soc
    nnz = data.A_eq.nnz + data.A_ge.nnz + (data.soc.nnz if data.soc is not None else 0) \
        + (data.P.nnz if data.P is not None else 0) + data.n
    D = float(data.n + rows)
    dense = D * (D + 1)
    return BASE_BYTES + SPARSE_BYTES * (nnz + 2 * data.n + rows) + DENSE_BYTES * dense


def _size_hint(solver: str) -> str:
    hint = ("lower the degree (a smaller Gram basis), exploit sparsity (add_sos(..., sparsity='correlative' or 'term'): "
            "one small Gram block per clique or term component), or use "
            "cone='dsos' (an LP) or cone='sdsos' (second-order cones) in add_sos: no dense blocks")
    return hint if solver == "SCS" else hint + ", or solver='SCS' (first order: no dense KKT blocks)"


def check_solver(solver: str) -> str:
    """The solver's name in capitals; InputError unless sosdyn or cvxpy knows it."""
    solver = solver.upper()
    if solver not in SOLVERS:
        import cvxpy as cp          # lazily (3 s): only a solver name outside SOLVERS needs it
        if solver not in cp.installed_solvers():
            raise InputError(f"unknown solver {solver!r}; use one of {SOLVERS} "
                             f"(installed in cvxpy: {cp.installed_solvers()})")
    return solver


def solve_program(program, solver, backend, scale, verbose, build=0.0, **settings) -> Solution:
    """Assemble ``program`` (its cached conic form) and solve it with the chosen back end.

    ``build`` is the declaration time reported in ``Solution.timings["build"]``. The program
    is not changed (``program.compile`` only caches its conic form). ``settings`` go to the
    solver, except ``affine_psd=True`` (direct back end only): PSD blocks fixed by their
    equality rows go to Clarabel as cones on affine expressions (:func:`~.conic.affine_cones`;
    e.g. a constant SOS-matrix constraint's Gram block: its variables and rows leave the KKT
    system).
    """
    solver = check_solver(solver)
    needs_cvxpy = bool(program.cvxpy_constraints) or (
        program.objective is not None and is_cvxpy(program.objective[1]))
    if backend == "auto":
        backend = "direct" if solver == "CLARABEL" and not needs_cvxpy else "cvxpy"
    if backend == "direct" and (solver != "CLARABEL" or needs_cvxpy):
        raise InputError("backend='direct' supports Clarabel without cvxpy constraints or "
                         "objectives; use backend='cvxpy'")
    if backend not in ("direct", "cvxpy"):
        raise InputError(f"unknown backend {backend!r}: use 'auto', 'direct' or 'cvxpy'")
    if backend != "direct" and settings.pop("affine_psd", False):
        raise InputError(f"affine_psd is a setting of the direct Clarabel back end, not of backend={backend!r}. "
                         "Try: backend='direct' (or 'auto' with Clarabel), or drop affine_psd")
    t0 = time.perf_counter()
    data = program.compile(scale=scale)
    canon = time.perf_counter() - t0
    if data.infeasible_reason:
        return Solution(program, data, "infeasible", np.full(data.n, np.nan), solver, backend,
                        {"build": build, "canonicalize": canon, "solve": 0.0},
                        raw_status="detected before solving", reason=data.infeasible_reason)
    check_data(data)
    if not (backend == "direct" and coarse_bytes(data) <= get_limits().max_bytes):   # else the estimate fits
        sizes = data.sizes()
        check_bytes(solver_bytes(data, solver, backend),
                    f"The {solver} solve ({backend} backend; {len(sizes['psd_blocks'])} PSD block(s), the "
                    f"largest {max(sizes['psd_blocks'], default=0)} x {max(sizes['psd_blocks'], default=0)}, "
                    f"{sizes['equalities']} equality rows)",
                    _size_hint(solver))
    crashed = False
    with native_stderr() as err:
        try:
            if backend == "direct":
                status, x, raw, seconds, info = _clarabel(data, verbose, settings)
            else:
                status, x, raw, seconds, info = _cvxpy(program, data, solver, verbose, settings)
        except InputError:
            raise
        except BaseException as exc:   # a solver crash (Clarabel's Rust panics too) becomes a status
            if isinstance(exc, INTERRUPTS):
                raise
            crashed = True
            status, x, raw, seconds, info = ("solver_error", np.full(data.n, np.nan),
                                             f"{type(exc).__name__}: {exc}", 0.0, {})
    if crashed:                        # the panic's text stays out of the terminal, kept for the message
        info["solver_stderr"] = err.text[-4000:]
    elif err.text:                     # anything else the solver printed there is passed on
        sys.stderr.write(err.text)
    if status in ("optimal", "optimal_inaccurate") and not np.abs(x).max(initial=0.0) <= MAX_COEFFICIENT:
        status, raw = "solver_error", raw + f" (solution not finite or above {MAX_COEFFICIENT:.0e})"
    timings = {"build": build, "canonicalize": canon, "solve": seconds}
    return Solution(program, data, status, x, solver, backend, timings, raw_status=raw, info=info)

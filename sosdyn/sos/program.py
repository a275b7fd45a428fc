"""SOS programs: declare decision variables and constraints; solving is a separate step.

An :class:`SOSProgram` holds data only. Every constraint becomes linear equalities (or
inequalities) over decision ids plus PSD cones over Gram blocks; :mod:`.conic` assembles
them into one standard-form problem and :mod:`.backends` hands it to a solver.

    p is SOS   <=>   p = z(x)^T Q z(x),  Q >= 0   (coefficient matching: G svec(Q) = coef(p))
"""
from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, PolynomialError, UnverifiedSolutionError
from ..poly import PolyMatrix, Polynomial, allocate, check_terms_size, monomials_up_to, variable_names
from ..poly.monomials import match_rows, unique_rows
from .gram import SQRT2, gram_matching, svec_pairs, svec_size
from .newton import newton_basis
from .objective import QuadraticForm, is_cvxpy

SOLVERS = ("CLARABEL", "SCS")


@dataclass
class Basis:
    """A monomial basis z(x) of a Gram matrix: exponent rows over ``vars``."""

    vars: tuple
    exps: np.ndarray

    def __len__(self) -> int:
        return self.exps.shape[0]

    def monomials(self) -> list:
        return [Polynomial(self.vars, e[None, :], [1.0]) for e in self.exps]

    def to_sympy(self) -> list:
        from ..poly import to_sympy
        return [to_sympy(m) for m in self.monomials()]

    def __repr__(self) -> str:
        return "Basis([" + ", ".join(repr(m) for m in self.monomials()) + "])"


@dataclass
class LinearRows:
    """Rows ``A d (= or >=) b`` over decision ids, as COO triplets."""

    name: str
    kind: str            # "eq" or "ge"
    rows: np.ndarray
    ids: np.ndarray
    vals: np.ndarray
    rhs: np.ndarray
    role: str = "user"   # "user" (add_eq/add_ge), "dsos" (auxiliary rows of a DSOS block)

    @classmethod
    def from_affine(cls, name, kind, coef, dec, offset_rows=None):
        """Rows ``coef[:, 1:] d + coef[:, 0] (= or >=) 0`` of an affine coefficient array."""
        r, c = np.nonzero(coef[:, 1:])
        rows = r if offset_rows is None else offset_rows[r]
        return cls(name, kind, rows, dec[c], coef[r, 1 + c], -coef[:, 0])


@dataclass
class PsdBlock:
    """A Gram (or LMI) block: decision ids of svec(Q), Q of size ``size``.

    ``cone`` "psd" (Q >= 0, an SDP block) or "dsos" (Q diagonally dominant with a
    nonnegative diagonal: linear inequalities only, an LP inner approximation of "psd").
    ``role`` says who owns it: "gram" (an SOS constraint's Gram matrix), "multiplier" (an
    SOS multiplier of add_nonneg_on), "sos_var" (new_sos) or "psd_var" (new_psd). Every
    block is checked by ``Solution.verify()``. Off the diagonal, Q_ij = s_k * SQRT2 / 2
    (s the svec entry): the one convention every expression built on a block uses.
    """

    name: str
    ids: np.ndarray
    size: int
    cone: str = "psd"
    role: str = "gram"


@dataclass
class Block:
    """A declared group of decision ids (free, or an svec of a PSD matrix)."""

    name: str
    ids: np.ndarray
    psd: PsdBlock | None = None


class Multiplier:
    """An SOS multiplier sigma >= 0 of ``add_nonneg_on``: sigma = z^T S z for ``constraint`` g >= 0.

    ``poly`` is sigma as a decision polynomial (``sol.value(m.poly)`` gives its numbers),
    ``basis`` is z, ``psd`` the Gram block of S; ``gram_matrix(sol)`` reads S from a solution.
    """

    def __init__(self, program, constraint: Polynomial, poly: Polynomial, basis: Basis, psd: PsdBlock):
        self.program, self.constraint, self.poly, self.basis, self.psd = program, constraint, poly, basis, psd

    def gram_matrix(self, solution=None) -> np.ndarray:
        """S of ``solution`` (default: the program's latest); raises unless it is verified."""
        return _solution_of(self, solution).gram_matrix(self)

    def value(self, solution=None) -> Polynomial:
        """sigma as a numeric polynomial at ``solution`` (default: the program's latest)."""
        return _solution_of(self, solution).value(self.poly)

    def __repr__(self) -> str:
        return f"Multiplier({self.psd.name!r} for {self.constraint!r} >= 0, basis size {len(self.basis)})"


@dataclass
class EqualityMultiplier:
    """A free multiplier lambda of an equality ``constraint`` h = 0 in ``add_nonneg_on``."""

    constraint: Polynomial
    poly: Polynomial


def _solution_of(handle, solution):
    sol = solution if solution is not None else handle.program.solution
    if sol is None:
        raise InputError(f"{handle!r} has no solution yet: call prog.solve() first")
    return sol


class SOSConstraint:
    """Handle of one SOS constraint "poly is SOS"; after a solve it holds the certificate.

    For ``add_nonneg_on``, ``source`` is the polynomial shown nonnegative, ``multipliers``
    the SOS multipliers (:class:`Multiplier`) and ``eq_multipliers`` the free ones; ``poly``
    is then source - sum sigma_i g_i - sum lambda_j h_j.
    """

    def __init__(self, program, name, kind, poly, basis, psd, multipliers=(), eq_multipliers=(),
                 source=None):
        self.program, self.name, self.kind = program, name, kind
        self.poly: Polynomial = poly
        self.basis: Basis = basis
        self.psd: PsdBlock = psd
        self.multipliers: list[Multiplier] = list(multipliers)
        self.eq_multipliers: list[EqualityMultiplier] = list(eq_multipliers)
        self.source: Polynomial = poly if source is None else source
        self._gram_exps, self._G = gram_matching(basis.exps)
        self.rows: LinearRows | None = None
        self.infeasible_reason: str | None = None
        self._match()

    def _match(self):
        """Coefficient matching coef(poly) = G svec(Q) as one block of sparse rows."""
        p = self.poly.with_vars(self.basis.vars)
        U, _ = unique_rows(np.vstack([p.exps, self._gram_exps]))
        idx_p = match_rows(U, p.exps)
        idx_g = match_rows(U, self._gram_exps)
        G = self._G.tocoo()
        prows = LinearRows.from_affine(self.name, "eq", p.coef, p.dec, idx_p)
        rhs = np.zeros(U.shape[0])
        rhs[idx_p] = p.coef[:, 0]
        self.rows = LinearRows(
            self.name, "eq",
            np.concatenate([prows.rows, idx_g[G.row]]),
            np.concatenate([prows.ids, self.psd.ids[G.col]]),
            np.concatenate([-prows.vals, G.data]),
            rhs)
        covered = np.zeros(U.shape[0], dtype=bool)
        covered[idx_g] = True
        covered[prows.rows] = True
        bad = np.flatnonzero(~covered & (rhs != 0))
        self.infeasible_reason = None if not bad.size else (
            f"constraint {self.name!r}: monomial "
            f"{Polynomial(self.basis.vars, U[bad[:1]], [1.0])!r} has a fixed non-zero coefficient "
            f"but cannot be produced by the Gram basis {self.basis!r}")

    def update(self, poly) -> "SOSConstraint":
        """Replace the polynomial by one with new numbers, keeping the Gram basis.

        This is the compile-once path: no Newton polytope, no Gram matching is recomputed.
        For ``add_nonneg_on`` the new polynomial is the new source p of "p >= 0 on the set";
        the multipliers stay.
        """
        if self.kind == "sos_matrix":
            poly, exps = self.program._matrix_form(poly)
        else:
            poly, exps = self.program._as_sos_polynomial(poly), None
        source = poly
        for m in self.multipliers + self.eq_multipliers:
            poly = poly - m.poly * m.constraint
        vars = self.basis.vars + tuple(v for v in poly.vars if v not in self.basis.vars)
        poly = poly.with_vars(vars)
        if vars != self.basis.vars or (match_rows(self._gram_exps, poly.exps) < 0).any():
            # the support outgrew the Gram basis: choose a new one (the only recompilation)
            exps = newton_basis(poly.exps) if exps is None else exps
            self.basis = Basis(poly.vars, exps if exps.shape[1] == len(poly.vars) else newton_basis(poly.exps))
            self.psd = self.program._replace_psd(self.psd, len(self.basis))
            self._gram_exps, self._G = gram_matching(self.basis.exps)
        self.poly, self.source = poly, source.with_vars(vars)
        self._match()
        self.program._invalidate()
        return self

    def gram_matrix(self, solution=None, checked: bool = True) -> np.ndarray:
        """The Gram matrix Q with poly = z^T Q z, read from ``solution``.

        ``solution`` defaults to the program's latest solve (``program.solution``), which a
        later re-solve replaces; pass the Solution (or call ``sol.gram_matrix(con)``) to read
        the one this certificate belongs to. Raises UnverifiedSolutionError / SolverError
        unless that solution passes the independent check; ``checked=False`` returns the
        solver's numbers anyway, for diagnostics only.
        """
        return _solution_of(self, solution).gram_matrix(self, checked=checked)

    def __repr__(self) -> str:
        return f"SOSConstraint({self.name!r}, kind={self.kind}, basis size {len(self.basis)})"


class FamilySOSConstraint(SOSConstraint):
    """sum_t w_t T_t is an SOS matrix for fixed terms T_t (see SOSProgram.add_sos_matrix_family)."""

    def __init__(self, program, name, term_polys, basis, psd, weights):
        U, _ = unique_rows(np.vstack([q.exps for q in term_polys]))
        self._dec = np.unique(np.concatenate([q.dec for q in term_polys] + [np.zeros(0, dtype=np.int64)]))
        self._tensor = np.zeros((len(term_polys), U.shape[0], 1 + self._dec.size))
        for t, q in enumerate(term_polys):
            q = q.with_dec(self._dec)
            self._tensor[t, match_rows(U, q.exps)] = q.coef
        self._U, self._vars = U, term_polys[0].vars
        self.weights = self._check_weights(weights)
        super().__init__(program, name, "sos_matrix", self._weighted(), basis, psd)

    def _check_weights(self, weights):
        w = np.asarray(weights, dtype=float)
        if w.shape != (self._tensor.shape[0],) or not np.isfinite(w).all():
            raise InputError(f"family {self.name if hasattr(self, 'name') else ''!r}: expected "
                             f"{self._tensor.shape[0]} finite weights, got shape {w.shape}")
        return w

    def _weighted(self) -> Polynomial:
        return Polynomial(self._vars, self._U, np.tensordot(self.weights, self._tensor, axes=1),
                          self._dec, canonical=True)

    def set_weights(self, weights) -> "FamilySOSConstraint":
        """New numbers, same structure: re-match without any polynomial algebra."""
        self.weights = self._check_weights(weights)
        self.poly = self.source = self._weighted()
        self._match()
        self.program._invalidate()
        return self

    def update(self, poly):
        raise InputError("a family constraint changes through set_weights(), not update()")


class SOSProgram:
    """A sum-of-squares program (see module docstring).

    >>> x, y = variables("x y"); prog = SOSProgram(); g = prog.new_var()
    >>> con = prog.add_sos(x**4 + y**4 - g); prog.maximize(g); sol = prog.solve()
    """

    def __init__(self, name: str = "sos"):
        self.name = name
        self.blocks: list[Block] = []
        self.sos_constraints: list[SOSConstraint] = []
        self.linear: list[LinearRows] = []
        self.cvxpy_constraints: list = []
        self.objective = None          # (sense, expression)
        self.solution = None
        self.build_seconds = 0.0      # total time spent declaring (all add_* calls)
        self.build_reported = 0.0     # part of it already charged to an earlier Solution
        self._compiled = None
        self.version = 0              # bumped by every change; a Solution records the one it solved
        self._cvx_vars: dict = {}
        self._counter = 0
        self._depth = 0
        self._forms: dict = {}

    # ------------------------------------------------------------------ naming / caching
    def _name(self, prefix, name):
        self._counter += 1
        return name or f"{prefix}{self._counter}"

    def _invalidate(self):
        self._compiled = None
        self.version += 1

    def _timed(fn):  # noqa: N805 -- decorator over methods
        def wrapper(self, *args, **kwargs):
            t0 = time.perf_counter()
            self._depth += 1
            try:
                return fn(self, *args, **kwargs)
            finally:
                self._depth -= 1
                if not self._depth:
                    self.build_seconds += time.perf_counter() - t0
                self._invalidate()
        wrapper.__doc__, wrapper.__name__ = fn.__doc__, fn.__name__
        return wrapper

    # ------------------------------------------------------------------ decision variables
    def _block(self, name, count, psd_size=None, role="gram") -> Block:
        ids = allocate(count)
        psd = PsdBlock(name, ids, psd_size, role=role) if psd_size is not None else None
        block = Block(name, ids, psd)
        self.blocks.append(block)
        return block

    def _replace_psd(self, psd: PsdBlock, size: int) -> PsdBlock:
        """Swap a Gram block for a new one of another size (blocks stay in id order)."""
        self.blocks = [b for b in self.blocks if b.psd is not psd]
        return self._block(psd.name, svec_size(size), size, psd.role).psd

    @_timed
    def new_var(self, shape=(), name=None):
        """Free scalar decision variable(s): a degree-0 Polynomial, or a PolyMatrix for a shape."""
        name = self._name("v", name)
        shape = (shape,) if isinstance(shape, int) else tuple(shape)
        size = int(np.prod(shape)) if shape else 1
        ids = self._block(name, size).ids
        scalars = [Polynomial.affine([i], [1.0]) for i in ids]
        if not shape:
            return scalars[0]
        return PolyMatrix(np.array(scalars, dtype=object).reshape(shape))

    @_timed
    def new_ids(self, count: int, name=None) -> np.ndarray:
        """Low level: ``count`` free scalar decision variables, returned as their ids.

        Build polynomials on them directly, e.g. ``Polynomial(vars, exps, coef, ids)``.
        """
        return self._block(self._name("ids", name), int(count)).ids

    @_timed
    def new_poly(self, vars, degree: int, min_degree: int = 0, name=None) -> Polynomial:
        """A polynomial in ``vars`` with all monomials of degree in [min_degree, degree] free."""
        names = variable_names(vars)
        exps = monomials_up_to(len(names), degree, min_degree)
        ids = self._block(self._name("poly", name), exps.shape[0]).ids
        return Polynomial(names, exps, np.hstack([np.zeros((len(ids), 1)), np.eye(len(ids))]), ids)

    def _gram_polynomial(self, basis: Basis, psd: PsdBlock) -> Polynomial:
        i, j = svec_pairs(len(basis))
        check_terms_size(i.size, basis.exps.shape[1], 1 + i.size, f"a Gram polynomial over {len(basis)} monomials")
        coef = np.zeros((i.size, 1 + i.size))
        coef[np.arange(i.size), 1 + np.arange(i.size)] = np.where(i == j, 1.0, SQRT2)
        return Polynomial(basis.vars, basis.exps[i] + basis.exps[j], coef, psd.ids)

    def _sos_block(self, vars, degree: int, name, role):
        """(z^T Q z, z, block of Q) for a new Gram block, z all monomials up to degree/2."""
        if degree < 0 or degree % 2:
            raise PolynomialError(f"an SOS polynomial has even degree, got {degree}")
        names = variable_names(vars)
        basis = Basis(names, monomials_up_to(len(names), degree // 2))
        psd = self._block(name, svec_size(len(basis)), len(basis), role).psd
        return self._gram_polynomial(basis, psd), basis, psd

    @_timed
    def new_sos(self, vars, degree: int, name=None) -> Polynomial:
        """An SOS polynomial z^T Q z, Q >= 0 a new Gram block, z all monomials up to degree/2."""
        return self._sos_block(vars, degree, self._name("sos", name), "sos_var")[0]

    @_timed
    def new_psd(self, n: int, name=None) -> PolyMatrix:
        """A constant symmetric matrix variable P >= 0 (an LMI block), as a PolyMatrix."""
        psd = self._block(self._name("psd", name), svec_size(n), n, "psd_var").psd
        i, j = svec_pairs(n)
        entries = np.empty((n, n), dtype=object)
        for k, (a, b) in enumerate(zip(i, j)):
            entries[a, b] = entries[b, a] = Polynomial.affine([psd.ids[k]], [1.0 if a == b else SQRT2 / 2])
        return PolyMatrix(entries)

    # ------------------------------------------------------------------ constraints
    @staticmethod
    def _as_sos_polynomial(expr):
        if isinstance(expr, (int, float)):
            expr = Polynomial.constant(float(expr))
        if not isinstance(expr, Polynomial):
            raise PolynomialError(f"add_sos takes a Polynomial, got {type(expr).__name__}; "
                                  "use add_sos_matrix for a PolyMatrix")
        return expr

    def _register(self, name, kind, poly, basis_exps, cone="psd", **handles):
        psd = self._block(name, svec_size(basis_exps.shape[0]), basis_exps.shape[0]).psd
        if cone == "dsos":
            psd.cone = "dsos"
            self._diagonally_dominant(psd)
        elif cone != "psd":
            raise InputError(f"unknown cone {cone!r}: use 'psd' (SOS) or 'dsos' (diagonally dominant SOS)")
        con = SOSConstraint(self, name, kind, poly, Basis(poly.vars, basis_exps), psd, **handles)
        self.sos_constraints.append(con)
        return con

    def _diagonally_dominant(self, psd: PsdBlock):
        """Q_ii >= sum_{j != i} t_ij, t_ij >= +-Q_ij (Ahmadi & Majumdar's DSOS, an LP)."""
        i, j = svec_pairs(psd.size)
        off = np.flatnonzero(i != j)
        t = self._block(f"{psd.name}.t", off.size).ids
        w = SQRT2 / 2                               # Q_ij = w s_k off the diagonal
        rows, ids, vals = [], [], []
        for r, k in enumerate(off):                 # t_k - w s_k >= 0 and t_k + w s_k >= 0
            rows += [2 * r, 2 * r, 2 * r + 1, 2 * r + 1]
            ids += [t[r], psd.ids[k], t[r], psd.ids[k]]
            vals += [1.0, -w, 1.0, w]
        base = 2 * off.size
        for d in range(psd.size):                   # Q_dd - sum_k t_k >= 0 over pairs touching d
            k_diag = np.flatnonzero((i == d) & (j == d))[0]
            touching = [r for r, k in enumerate(off) if i[k] == d or j[k] == d]
            rows += [base + d] * (1 + len(touching))
            ids += [psd.ids[k_diag]] + [t[r] for r in touching]
            vals += [1.0] + [-1.0] * len(touching)
        self.linear.append(LinearRows(f"{psd.name} (dsos)", "ge", np.array(rows, dtype=np.int64),
                                      np.array(ids, dtype=np.int64), np.array(vals),
                                      np.zeros(base + psd.size), role="dsos"))

    @_timed
    def add_sos(self, expr, basis=None, name=None, cone="psd") -> SOSConstraint:
        """Constrain the polynomial ``expr`` to be a sum of squares.

        The Gram basis comes from the Newton polytope of ``expr``'s support unless ``basis``
        (monomial Polynomials or an exponent array) is given, in which case it is honoured.
        ``cone="dsos"`` asks for a diagonally dominant Gram matrix instead (an LP; a
        stronger condition, so a smaller feasible set, that scales to large bases).
        """
        p = self._as_sos_polynomial(expr)
        name = self._name("sos", name)
        if basis is None:
            exps = newton_basis(p.exps)
        else:
            exps = self._basis_exps(basis, p)
            p = p.with_vars(p.vars + tuple(v for v in self._basis_vars(basis) if v not in p.vars))
        return self._register(name, "sos", p, exps, cone=cone)

    @staticmethod
    def _basis_vars(basis):
        if isinstance(basis, np.ndarray):
            return ()
        out: list = []
        for m in basis:
            out += [v for v in m.vars if v not in out]
        return tuple(out)

    def _basis_exps(self, basis, p):
        if isinstance(basis, np.ndarray):
            exps = np.asarray(basis, dtype=np.int64).reshape(-1, p.nvars)
        else:
            vars = p.vars + tuple(v for v in self._basis_vars(basis) if v not in p.vars)
            mons = [m.with_vars(vars) for m in basis]
            if any(m.nterms != 1 or not m.is_numeric for m in mons):
                raise PolynomialError("a basis is a list of monomials such as [x**2, x*y, 1]")
            exps = np.vstack([m.exps for m in mons])
        if unique_rows(exps)[0].shape[0] != exps.shape[0]:
            raise PolynomialError("the given basis has repeated monomials")
        return exps

    @staticmethod
    def _matrix_form(P, basis_from=None, with_basis=True):
        """y^T P(x) y as a scalar polynomial in (x, y), and the multipartite basis y (x) z(x).

        z_i comes from the Newton polytope of P_ii, or of the union of the P_ii of the
        matrices ``basis_from`` (a list sharing P's shape) when given.
        """
        if not isinstance(P, PolyMatrix):
            P = PolyMatrix(P)
        P.check_symmetric("matrix given to add_sos_matrix")
        r = P.shape[0]
        sources = [P] if basis_from is None else basis_from
        xvars: tuple = ()
        for S in sources + [P]:
            xvars = xvars + tuple(v for v in S.vars if v not in xvars)
        yvars = tuple(f"_y{i}" for i in range(r))
        allv = xvars + yvars
        entries = [(i, j, P.entries[i, j].with_vars(xvars)) for i in range(r) for j in range(i, r)]
        dec = np.unique(np.concatenate([e.dec for _, _, e in entries] + [np.zeros(0, dtype=np.int64)]))
        exps, coef = [], []
        for i, j, e in entries:            # y^T P y = sum_i P_ii y_i^2 + 2 sum_{i<j} P_ij y_i y_j
            y = np.zeros((e.nterms, r), dtype=np.int64)
            y[:, i] += 1
            y[:, j] += 1
            exps.append(np.hstack([e.exps, y]))
            coef.append(e.with_dec(dec).coef * (1.0 if i == j else 2.0))
        q = Polynomial(allv, np.vstack(exps), np.vstack(coef), dec)
        rows = []
        for i in range(r):
            if with_basis:
                support = np.vstack([S.entries[i, i].with_vars(xvars).exps for S in sources])
                z = newton_basis(unique_rows(support)[0])
                rows.append(np.hstack([z, np.tile(np.eye(r, dtype=np.int64)[i], (z.shape[0], 1))]))
        return q, np.vstack(rows) if rows else np.zeros((0, len(allv)), dtype=np.int64)

    def _cached_form(self, P: PolyMatrix) -> Polynomial:
        """y^T P y, expanded once per matrix object (families often share terms)."""
        key = id(P)
        if key not in self._forms or self._forms[key][0] is not P:
            self._forms[key] = (P, self._matrix_form(P, with_basis=False)[0])
        return self._forms[key][1]

    @_timed
    def add_sos_matrix_family(self, terms, weights, name=None) -> "FamilySOSConstraint":
        """sum_t weights[t] * terms[t] is an SOS matrix; the weights can change between solves.

        This is the compile-once path for parametrised problems (cvxpy's Parameters): each
        term is expanded and matched once; ``con.set_weights(w)`` re-solves with new numbers
        at the cost of one dense contraction. The Gram basis covers every term's support.
        """
        terms = [t if isinstance(t, PolyMatrix) else PolyMatrix(t) for t in terms]
        if not terms or len({t.shape for t in terms}) != 1:
            raise PolynomialError("add_sos_matrix_family needs a non-empty list of equal-shape matrices")
        name = self._name("family", name)
        q0, exps = self._matrix_form(terms[0], basis_from=terms)
        qs = [q0] + [self._cached_form(t) for t in terms[1:]]
        psd = self._block(name, svec_size(exps.shape[0]), exps.shape[0]).psd
        vars = qs[0].vars
        con = FamilySOSConstraint(self, name, [q.with_vars(vars) for q in qs], Basis(vars, exps), psd, weights)
        self.sos_constraints.append(con)
        return con

    @_timed
    def add_sos_matrix(self, P, name=None) -> SOSConstraint:
        """Constrain the symmetric polynomial matrix P(x) to be an SOS matrix.

        Equivalent to y^T P(x) y being SOS in (x, y), with the multipartite Gram basis
        y_i * z_i(x), z_i from the Newton polytope of P_ii (never a dense basis in (x, y)).
        A constant P gives a plain LMI P >= 0.
        """
        name = self._name("sosmat", name)
        q, exps = self._matrix_form(P)
        return self._register(name, "sos_matrix", q, exps)

    @_timed
    def add_nonneg_on(self, expr, ineqs=(), eqs=(), degree=None, name=None) -> SOSConstraint:
        """expr >= 0 on {g_i >= 0, h_j = 0} via Putinar/S-procedure multipliers.

        expr - sum_i sigma_i g_i - sum_j lambda_j h_j is SOS, sigma_i SOS and lambda_j free,
        each multiplier of the largest degree with deg(multiplier * constraint) <= degree.
        """
        p = self._as_sos_polynomial(expr)
        ineqs, eqs = list(ineqs), list(eqs)
        allv = p.vars
        for g in ineqs + eqs:
            allv = allv + tuple(v for v in g.vars if v not in allv)
        degree = degree if degree is not None else max([p.degree] + [g.degree for g in ineqs + eqs])
        name = self._name("nonneg", name)
        source = p.with_vars(allv)
        rest, mults, eq_mults = source, [], []
        for k, g in enumerate(ineqs):
            d = degree - g.degree
            d -= d % 2
            if d < 0:
                raise PolynomialError(f"degree {degree} is below the degree of constraint g{k} ({g.degree})")
            g = g.with_vars(allv)
            sigma, basis, psd = self._sos_block(allv, d, f"{name}.sigma{k}", "multiplier")
            mults.append(Multiplier(self, g, sigma, basis, psd))
            rest = rest - sigma * g
        for k, h in enumerate(eqs):
            d = degree - h.degree
            if d < 0:
                raise PolynomialError(f"degree {degree} is below the degree of equality h{k} ({h.degree})")
            h = h.with_vars(allv)
            lam = self.new_poly(allv, d, name=f"{name}.lambda{k}")
            eq_mults.append(EqualityMultiplier(h, lam))
            rest = rest - lam * h
        return self._register(name, "nonneg_on", rest, newton_basis(rest.exps), multipliers=mults,
                              eq_multipliers=eq_mults, source=source)

    @staticmethod
    def _affine_items(lhs, rhs):
        diff = lhs - rhs
        if isinstance(diff, PolyMatrix):
            return list(diff.entries.flat)
        if isinstance(diff, Polynomial):
            return [diff]
        raise PolynomialError(f"cannot constrain an expression of type {type(diff).__name__}")

    def _add_linear(self, name, kind, items) -> LinearRows:
        """One row per coefficient of every affine polynomial in ``items`` (= 0 or >= 0)."""
        parts, offset = [], 0
        for p in items:
            parts.append(LinearRows.from_affine(name, kind, p.coef, p.dec, offset + np.arange(p.nterms)))
            offset += p.nterms
        cat = lambda field, dtype: np.concatenate([getattr(q, field) for q in parts] + [np.zeros(0, dtype)])  # noqa: E731
        con = LinearRows(name, kind, cat("rows", np.int64), cat("ids", np.int64), cat("vals", float),
                         cat("rhs", float))
        self.linear.append(con)
        return con

    @_timed
    def add_eq(self, lhs, rhs=0.0, name=None) -> LinearRows:
        """lhs == rhs, coefficient by coefficient (polynomials or polynomial matrices)."""
        return self._add_linear(self._name("eq", name), "eq", self._affine_items(lhs, rhs))

    @_timed
    def add_ge(self, lhs, rhs=0.0, name=None) -> LinearRows:
        """lhs >= rhs for degree-0 affine expressions (element-wise for matrices)."""
        items = self._affine_items(lhs, rhs)
        if any(not p.is_constant for p in items):
            raise PolynomialError("add_ge takes constant affine expressions; use add_sos or "
                                  "add_nonneg_on for polynomial inequalities")
        return self._add_linear(self._name("ge", name), "ge", items)

    def add_constraint(self, constraint):
        """Add a cvxpy constraint written with :meth:`expr`; solves then go through cvxpy."""
        import cvxpy as cp
        if not isinstance(constraint, cp.constraints.constraint.Constraint):
            raise InputError(f"add_constraint takes a cvxpy constraint, got {type(constraint).__name__}")
        self.cvxpy_constraints.append(constraint)
        self._invalidate()
        return constraint

    # ------------------------------------------------------------------ objective
    def _set_objective(self, sense, expr):
        if isinstance(expr, (int, float)):
            expr = Polynomial.constant(float(expr))
        if isinstance(expr, Polynomial) and not expr.is_constant:
            raise PolynomialError(f"the objective must not depend on x; got {expr!r}. Maximise a "
                                  "coefficient (p.coeff(...)) or a new variable bounded by SOS constraints")
        if isinstance(expr, QuadraticForm) and sense == "max":
            raise InputError("maximising a convex quadratic is not a convex problem; minimise it instead")
        if not (isinstance(expr, (Polynomial, QuadraticForm)) or is_cvxpy(expr)):
            raise InputError(f"unsupported objective type {type(expr).__name__}")
        self.objective = (sense, expr)
        self._invalidate()

    def minimize(self, expr):
        """Minimise an affine scalar, a QuadraticForm (sum_squares) or a cvxpy expression."""
        self._set_objective("min", expr)

    def maximize(self, expr):
        """Maximise an affine scalar or a concave cvxpy expression."""
        self._set_objective("max", expr)

    # ------------------------------------------------------------------ cvxpy interop
    def expr(self, item):
        """The cvxpy expression of a degree-0 affine Polynomial (or PolyMatrix) of this program."""
        from .conic import cvxpy_affine
        return cvxpy_affine(self, item)

    # ------------------------------------------------------------------ solving
    @property
    def ids(self) -> np.ndarray:
        return np.concatenate([b.ids for b in self.blocks] + [np.zeros(0, dtype=np.int64)])

    @property
    def psd_blocks(self) -> list:
        return [b.psd for b in self.blocks if b.psd is not None and b.psd.cone == "psd"]

    def compile(self, scale: bool = True):
        """Assemble (and cache) the standard conic form; see :mod:`sosdyn.sos.conic`."""
        from .conic import assemble
        if self._compiled is None or self._compiled.scaled != scale:
            self._compiled = assemble(self, scale=scale)
        return self._compiled

    def tightened(self, kept: dict, margins: dict) -> "SOSProgram":
        """A copy whose Gram blocks are tightened: Q[K, K] >= eps I and Q = 0 outside K.

        ``kept`` maps id(PsdBlock) to the kept indices K (default all), ``margins`` to eps
        (default 0). Each block (PSD or DSOS) becomes Q[K, K] = P + eps I with P a new block
        in the same cone; its other rows and columns are fixed to zero (the face a solution
        of this program lies on). Objective, constraints and decision ids are shared with
        this program. Used by rigorous bounds (``Solution.rigorous_bound``).
        """
        clone = copy.copy(self)
        clone.name = f"{self.name} (tightened)"
        clone.blocks = [Block(b.name, b.ids) if b.psd is not None and b.psd.cone == "psd" else b
                        for b in self.blocks]
        clone.linear, clone.sos_constraints = list(self.linear), list(self.sos_constraints)
        clone.solution, clone._compiled, clone._forms, clone._cvx_vars = None, None, {}, {}
        for b in self.blocks:
            if b.psd is None or not b.psd.size:
                continue
            n = b.psd.size
            K = np.asarray(kept.get(id(b.psd), np.arange(n)), dtype=np.int64)
            i, j = svec_pairs(n)
            zero = np.flatnonzero(~(np.isin(i, K) & np.isin(j, K)))
            rows = [LinearRows(f"{b.name} face", "eq", np.arange(zero.size), b.ids[zero],
                               np.ones(zero.size), np.zeros(zero.size))]
            if K.size:
                inner = clone._block(f"{b.name}.interior", svec_size(K.size), K.size, b.psd.role).psd
                if b.psd.cone == "dsos":
                    inner.cone = "dsos"
                    clone._diagonally_dominant(inner)
                a, c = svec_pairs(K.size)
                outer = K[c] * (K[c] + 1) // 2 + K[a]          # svec index of (K[a], K[c])
                k = a.size
                rows.append(LinearRows(f"{b.name} = interior + eps I", "eq",
                                       np.concatenate([np.arange(k), np.arange(k)]),
                                       np.concatenate([b.ids[outer], inner.ids]),
                                       np.concatenate([np.ones(k), -np.ones(k)]),
                                       np.where(a == c, float(margins.get(id(b.psd), 0.0)), 0.0)))
            clone.linear += rows
        return clone

    def solve(self, solver: str = "CLARABEL", backend: str = "auto", scale: bool = True,
              verbose: bool = False, raise_on_failure: bool = False, rigorous: bool = False,
              **settings):
        """Solve and return a :class:`~sosdyn.sos.solution.Solution`.

        ``backend``: "direct" hands the conic data straight to Clarabel (no canonicalisation;
        the fast re-solve path); "cvxpy" goes through cvxpy (any cvxpy solver, and needed for
        cvxpy constraints/objectives); "auto" picks direct when it can.
        ``raise_on_failure``: raise SolverError/InfeasibleError/UnverifiedSolutionError
        instead of returning a Solution that is not verified.
        ``rigorous``: the objective (and every value) is read at a point where the whole
        certificate holds exactly: ``sol.objective`` is the proven bound, ``sol.bound``
        compares it with the solver's value (see :mod:`sosdyn.sos.solution`).
        """
        from .backends import solve_program
        solver = solver.upper()
        if solver not in SOLVERS:
            import cvxpy as cp
            if solver not in cp.installed_solvers():
                raise InputError(f"unknown solver {solver!r}; use one of {SOLVERS} "
                                 f"(installed in cvxpy: {cp.installed_solvers()})")
        sol = solve_program(self, solver=solver, backend=backend, scale=scale, verbose=verbose, **settings)
        self.solution = sol
        sol.rigorous = rigorous
        sol.verify()                        # now, while the program is the one that was solved
        if rigorous and sol.verified:
            try:
                sol.rigorous_bound()        # now, so its time is in sol.timings["rigorous"]
            except UnverifiedSolutionError:
                pass                        # raised again, with its reason, when a number is asked for
        if raise_on_failure:
            sol.raise_for_status()
        return sol

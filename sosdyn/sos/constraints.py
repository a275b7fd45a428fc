"""The pieces an SOS program is declared from: Gram bases, blocks, rows and constraint handles.

* :class:`Basis` -- a monomial basis z(x) (exponent rows over ``vars``);
* :class:`PsdBlock` / :class:`Block` -- decision ids of a Gram matrix Q (svec layout,
  :mod:`.gram`) or of free variables; :class:`LinearRows` -- rows ``A d (= or >=) b``;
* :class:`SOSConstraint` -- "p is SOS": coefficient matching coef(p) = G svec(Q) as one block
  of sparse equality rows (G from :func:`.gram.gram_matching`);
  :class:`FamilySOSConstraint` -- sum_t w_t T_t is an SOS matrix, weights changeable;
  :class:`Multiplier` / :class:`EqualityMultiplier` -- the multipliers of ``add_nonneg_on``;
* functions on arrays: :func:`matrix_form` (y^T P(x) y and its multipartite basis),
  :func:`gram_polynomial` (z^T Q z as a decision polynomial), :func:`user_basis`
  (a user's basis). The rows that put a Gram block in a smaller cone live in :mod:`.cones`.

A handle reads numbers only from a solution it is given: ``con.gram_matrix(sol)`` is
``sol.gram_matrix(con)``; the program never stores a solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, PolynomialError
from ..poly import PolyMatrix, Polynomial, check_terms_size, match_rows, to_sympy, unique_rows
from .gram import SQRT2, gram_matching, svec_pairs
from .newton import newton_basis
from .sizes import check_family_size

NO_SOLUTION_HINT = "pass the solution: sol.gram_matrix(con)"
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
        return [to_sympy(m) for m in self.monomials()]

    def __repr__(self) -> str:
        return "Basis([" + ", ".join(repr(m) for m in self.monomials()) + "])"


@dataclass
class LinearRows:
    """Rows ``A d (= or >=) b`` over decision ids, as COO triplets.

    ``kind`` "soc": rows 3k, 3k+1, 3k+2 of ``A d - b`` are (t, u, v) of one second-order cone
    t >= ||(u, v)||_2 (b = 0; these rows are never rescaled).
    """

    name: str
    kind: str            # "eq", "ge" or "soc"
    rows: np.ndarray
    ids: np.ndarray
    vals: np.ndarray
    rhs: np.ndarray
    role: str = "user"   # "user" (add_eq/add_ge), "dsos"/"sdsos" (auxiliary rows of such a block)

    @classmethod
    def from_affine(cls, name, kind, coef, ids, offset_rows=None):
        """Rows ``coef[:, 1:] d + coef[:, 0] (= or >=) 0`` of an affine coefficient array."""
        r, c = np.nonzero(coef[:, 1:])
        rows = r if offset_rows is None else offset_rows[r]
        return cls(name, kind, rows, ids[c], coef[r, 1 + c], -coef[:, 0])


@dataclass
class PsdBlock:
    """A Gram (or LMI) block: decision ids of svec(Q), Q of size ``size``.

    ``cone`` "psd" (Q >= 0, an SDP block), "sdsos" (Q scaled diagonally dominant: linear
    rows and 3-dimensional second-order cones, :func:`.cones.sdsos_rows`) or "dsos" (Q diagonally
    dominant with a nonnegative diagonal: linear inequalities only); see the module docstring.
    ``role`` says who owns it: "gram" (an SOS constraint's Gram matrix), "clique" (a further
    Gram block of a sparse constraint), "multiplier" (an SOS multiplier of add_nonneg_on),
    "sos_var" (new_sos) or "psd_var" (new_psd). Every
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


def _need(handle, solution):
    if solution is None:
        raise InputError(f"{handle!r}: no solution given; a program does not keep its solutions. "
                         f"Try: {NO_SOLUTION_HINT}, with sol = prog.solve()")
    return solution


class Multiplier:
    """An SOS multiplier sigma >= 0 of ``add_nonneg_on``: sigma = z^T S z for ``constraint`` g >= 0.

    ``poly`` is sigma as a decision polynomial (``sol.value(m.poly)`` gives its numbers),
    ``basis`` is z, ``psd`` the Gram block of S; ``gram_matrix(sol)`` reads S from a solution.
    """

    def __init__(self, constraint: Polynomial, poly: Polynomial, basis: Basis, psd: PsdBlock):
        self.constraint, self.poly, self.basis, self.psd = constraint, poly, basis, psd

    def gram_matrix(self, solution=None, checked: bool = True) -> np.ndarray:
        """S at ``solution`` (required); raises unless the solution is verified."""
        return _need(self, solution).gram_matrix(self, checked=checked)

    def value(self, solution=None) -> Polynomial:
        """sigma as a numeric polynomial at ``solution`` (required)."""
        return _need(self, solution).value(self.poly)

    def __repr__(self) -> str:
        return f"Multiplier({self.psd.name!r} for {self.constraint!r} >= 0, basis size {len(self.basis)})"


@dataclass
class EqualityMultiplier:
    """A free multiplier lambda of an equality ``constraint`` h = 0 in ``add_nonneg_on``."""

    constraint: Polynomial
    poly: Polynomial


class SOSConstraint:
    """Handle of one SOS constraint "poly is SOS": its basis, Gram block and matching rows.

    For ``add_nonneg_on``, ``source`` is the polynomial shown nonnegative, ``multipliers``
    the SOS multipliers (:class:`Multiplier`) and ``eq_multipliers`` the free ones; ``poly``
    is then source - sum sigma_i g_i - sum lambda_j h_j. A sparse constraint (``sparsity=``)
    has further Gram blocks sigma_k = z_k^T Q_k z_k, kept as multipliers of the constant 1
    (role "clique"), so poly = source - sum_k sigma_k - ...; ``gram_blocks`` lists them all.
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
        self._gram_exps, self._gram_rows, self._gram_weights = gram_matching(basis.exps)
        self._layout_memo = None
        self.rows: LinearRows | None = None
        self.infeasible_reason: str | None = None
        self._match()

    def _layout(self, exps):
        """(U, rows of p's monomials ``exps`` in U, rows of the Gram products in U), U their
        union; remembered while p's monomials stay the same (a re-solve with new numbers)."""
        memo = self._layout_memo
        if memo is not None and np.array_equal(memo[0], exps):
            return memo[1]
        idx_p = match_rows(self._gram_exps, exps)
        if (idx_p >= 0).all():        # p's monomials among the Gram products': U is theirs
            layout = (self._gram_exps, idx_p, np.arange(self._gram_exps.shape[0]))
        else:
            U, _ = unique_rows(np.vstack([exps, self._gram_exps]))
            layout = (U, match_rows(U, exps), match_rows(U, self._gram_exps))
        self._layout_memo = (exps, layout)
        return layout

    def _match(self):
        """Coefficient matching coef(poly) = G svec(Q) as one block of sparse rows."""
        p = self.poly.with_vars(self.basis.vars)
        U, idx_p, idx_g = self._layout(p.exps)
        prows = LinearRows.from_affine(self.name, "eq", p.coef, p.ids, idx_p)
        rhs = np.zeros(U.shape[0])
        rhs[idx_p] = p.coef[:, 0]
        self.rows = LinearRows(
            self.name, "eq",
            np.concatenate([prows.rows, idx_g[self._gram_rows]]),
            np.concatenate([prows.ids, self.psd.ids]),
            np.concatenate([-prows.vals, self._gram_weights]),
            rhs)
        covered = np.zeros(U.shape[0], dtype=bool)
        covered[idx_g] = covered[prows.rows] = True
        bad = np.flatnonzero(~covered & (rhs != 0))
        self.infeasible_reason = None if not bad.size else (
            f"constraint {self.name!r}: monomial "
            f"{Polynomial(self.basis.vars, U[bad[:1]], [1.0])!r} has a fixed non-zero coefficient "
            f"but cannot be produced by the Gram basis {self.basis!r}")

    @property
    def gram_blocks(self) -> list:
        """(Basis, PsdBlock) of every Gram block of the certificate of ``source``: the main one,
        then the clique blocks of a sparse constraint (not the multipliers of add_nonneg_on)."""
        return [(self.basis, self.psd)] + [(m.basis, m.psd) for m in self.multipliers if m.psd.role == "clique"]

    def update(self, poly) -> "SOSConstraint":
        """Replace the polynomial by one with new numbers, keeping the Gram basis.

        This is the compile-once path: no Newton polytope, no Gram matching is recomputed.
        For ``add_nonneg_on`` the new polynomial is the new source p of "p >= 0 on the set";
        the multipliers stay.
        """
        if self.kind == "sos_matrix":
            poly, exps = matrix_form(poly)
        else:
            poly, exps = as_sos_polynomial(poly), None
        source = poly
        for m in self.multipliers + self.eq_multipliers:
            poly = poly - m.poly * m.constraint
        vars = self.basis.vars + tuple(v for v in poly.vars if v not in self.basis.vars)
        poly = poly.with_vars(vars)
        if vars != self.basis.vars or (match_rows(self._gram_exps, poly.exps) < 0).any():
            # the support outgrew the Gram basis: choose a new one (the only recompilation)
            exps = newton_basis(poly.exps) if exps is None else exps
            self.basis = Basis(poly.vars, exps if exps.shape[1] == len(poly.vars) else newton_basis(poly.exps))
            self.psd = self.program.replace_gram_block(self.psd, len(self.basis))
            self._gram_exps, self._gram_rows, self._gram_weights = gram_matching(self.basis.exps)
            self._layout_memo = None
        self.poly, self.source = poly, source.with_vars(vars)
        self._match()
        self.program.mark_changed()
        return self

    def gram_matrix(self, solution=None, checked: bool = True) -> np.ndarray:
        """The Gram matrix Q with poly = z^T Q z at ``solution`` (required): ``sol.gram_matrix(con)``.

        Raises UnverifiedSolutionError / SolverError unless that solution passes the
        independent check; ``checked=False`` returns the solver's numbers anyway, for
        diagnostics only.
        """
        return _need(self, solution).gram_matrix(self, checked=checked)

    def __repr__(self) -> str:
        return f"SOSConstraint({self.name!r}, kind={self.kind}, basis size {len(self.basis)})"


class FamilySOSConstraint(SOSConstraint):
    """sum_t w_t T_t is an SOS matrix for fixed terms T_t (see SOSProgram.add_sos_matrix_family)."""

    def __init__(self, program, name, term_polys, basis, psd, weights):
        U, _ = unique_rows(np.vstack([q.exps for q in term_polys]))
        self._ids = np.unique(np.concatenate([q.ids for q in term_polys] + [np.zeros(0, dtype=np.int64)]))
        check_family_size(len(term_polys), U.shape[0], self._ids.size, name)
        self._tensor = np.zeros((len(term_polys), U.shape[0], 1 + self._ids.size))
        for t, q in enumerate(term_polys):
            q = q.with_ids(self._ids)
            self._tensor[t, match_rows(U, q.exps)] = q.coef
        self._U, self._vars = U, term_polys[0].vars
        self.weights = self._check_weights(weights, name)
        super().__init__(program, name, "sos_matrix", self._weighted(), basis, psd)

    def _check_weights(self, weights, name):
        w = np.asarray(weights, dtype=float)
        if w.shape != (self._tensor.shape[0],) or not np.isfinite(w).all():
            raise InputError(f"family {name!r}: expected {self._tensor.shape[0]} finite weights, got shape {w.shape}")
        return w

    def _weighted(self) -> Polynomial:
        return Polynomial(self._vars, self._U, np.tensordot(self.weights, self._tensor, axes=1), self._ids, canonical=True)

    def set_weights(self, weights) -> "FamilySOSConstraint":
        """New numbers, same structure: re-match without any polynomial algebra."""
        self.weights = self._check_weights(weights, self.name)
        self.poly = self.source = self._weighted()
        self._match()
        self.program.mark_changed()
        return self

    def update(self, poly):
        raise InputError("a family constraint changes through set_weights(), not update()")


# ---------------------------------------------------------------------- functions on arrays
def as_sos_polynomial(expr) -> Polynomial:
    """A number or Polynomial given to add_sos, as a Polynomial (PolynomialError otherwise)."""
    if isinstance(expr, (int, float)):
        expr = Polynomial.constant(float(expr))
    if not isinstance(expr, Polynomial):
        raise PolynomialError(f"add_sos takes a Polynomial, got {type(expr).__name__}; "
                              "use add_sos_matrix for a PolyMatrix")
    return expr


def helper_names(r: int, taken) -> tuple:
    """r new variable names ``_y0 .. _y<r-1>``, with as many leading underscores as it takes
    for none of them to be in ``taken`` (so they never collide with a user's variables)."""
    taken, prefix = set(taken), "_y"
    while any(f"{prefix}{i}" in taken for i in range(r)):
        prefix = "_" + prefix
    return tuple(f"{prefix}{i}" for i in range(r))


def matrix_form(P, basis_from=None, with_basis=True, taken=()):
    """y^T P(x) y as a scalar polynomial in (x, y), and the multipartite basis y (x) z(x).

    y^T P y = sum_i P_ii y_i^2 + 2 sum_{i<j} P_ij y_i y_j over new variables y_i
    (:func:`helper_names`, unique against the variables of P, ``basis_from`` and ``taken``).
    z_i comes from the Newton polytope of P_ii, or of the union of the P_ii of the matrices
    ``basis_from`` (a list sharing P's shape) when given; the basis rows are y_i z_i(x).
    With ``with_basis=False`` the basis is empty (only the scalar form is wanted).
    """
    if not isinstance(P, PolyMatrix):
        P = PolyMatrix(P)
    P.check_symmetric("matrix given to add_sos_matrix")
    r = P.shape[0]
    sources = [P] if basis_from is None else basis_from
    xvars: tuple = ()
    for S in sources + [P]:
        xvars = xvars + tuple(v for v in S.vars if v not in xvars)
    yvars = helper_names(r, xvars + tuple(taken))
    allv = xvars + yvars
    t = P.terms(xvars)                                 # the upper triangle's terms, vectorised
    t = t.select(t.row <= t.col)
    y = np.zeros((t.row.size, r), dtype=np.int64)
    np.add.at(y, (np.arange(t.row.size), t.row), 1)
    np.add.at(y, (np.arange(t.row.size), t.col), 1)
    ids = np.unique(t.did[t.did >= 0])
    coef = np.zeros((t.row.size, 1 + ids.size))
    coef[np.arange(t.row.size), np.where(t.did >= 0, 1 + np.searchsorted(ids, t.did), 0)] = \
        t.val * np.where(t.row == t.col, 1.0, 2.0)
    q = Polynomial(allv, np.hstack([t.exps, y]), coef, ids)
    rows = []
    for i in range(r):
        if with_basis:
            support = np.vstack([S.entries[i, i].with_vars(xvars).exps for S in sources])
            z = newton_basis(unique_rows(support)[0])
            rows.append(np.hstack([z, np.tile(np.eye(r, dtype=np.int64)[i], (z.shape[0], 1))]))
    return q, np.vstack(rows) if rows else np.zeros((0, len(allv)), dtype=np.int64)


def gram_polynomial(basis: Basis, psd: PsdBlock) -> Polynomial:
    """z^T Q z as a polynomial affine in the svec entries of Q (the ids of ``psd``)."""
    i, j = svec_pairs(len(basis))
    check_terms_size(i.size, basis.exps.shape[1], 1 + i.size, f"a Gram polynomial over {len(basis)} monomials")
    coef = np.zeros((i.size, 1 + i.size))
    coef[np.arange(i.size), 1 + np.arange(i.size)] = np.where(i == j, 1.0, SQRT2)
    return Polynomial(basis.vars, basis.exps[i] + basis.exps[j], coef, psd.ids)


def affine_items(lhs, rhs) -> list:
    """The affine polynomials of ``lhs - rhs`` (one, or every entry of a matrix)."""
    diff = lhs - rhs
    if isinstance(diff, PolyMatrix):
        return list(diff.entries.flat)
    if isinstance(diff, Polynomial):
        return [diff]
    raise PolynomialError(f"cannot constrain an expression of type {type(diff).__name__}")


def affine_rows(name, kind, items) -> LinearRows:
    """One row per coefficient of every affine polynomial in ``items`` (= 0 or >= 0)."""
    parts, offset = [], 0
    for p in items:
        parts.append(LinearRows.from_affine(name, kind, p.coef, p.ids, offset + np.arange(p.nterms)))
        offset += p.nterms

    def cat(field, dtype):
        return np.concatenate([getattr(q, field) for q in parts] + [np.zeros(0, dtype)])
    return LinearRows(name, kind, cat("rows", np.int64), cat("ids", np.int64), cat("vals", float), cat("rhs", float))


def basis_monomials(basis) -> list:
    """A user's basis as monomial Polynomials: numbers (the monomial 1) and one-term polynomials."""
    if isinstance(basis, (Polynomial, int, float)):
        basis = [basis]
    out = []
    for m in np.asarray(basis, dtype=object).ravel() if isinstance(basis, np.ndarray) else basis:
        if isinstance(m, (int, float, np.integer, np.floating)) and not isinstance(m, bool) and m != 0:
            m = Polynomial.constant(1.0)
        if not isinstance(m, Polynomial) or m.nterms != 1 or not m.is_numeric:
            raise PolynomialError(f"a basis is a list of monomials such as [1, x, x*y, x**2]; got {m!r}")
        out.append(m)
    return out


def user_basis(basis, p: Polynomial):
    """(p over its variables + the basis's, the basis's exponent rows over those variables) for a
    user's basis: monomials (numbers count as the monomial 1) or an integer exponent array over p.vars."""
    if isinstance(basis, np.ndarray) and basis.dtype != object:
        exps = np.asarray(basis, dtype=np.int64).reshape(-1, p.nvars)
    else:
        mons = basis_monomials(basis)
        for m in mons:
            p = p.with_vars(p.vars + tuple(v for v, e in zip(m.vars, m.exps[0]) if e and v not in p.vars))
        exps = np.vstack([m.with_vars(p.vars).exps for m in mons])
    if unique_rows(exps)[0].shape[0] != exps.shape[0]:
        raise PolynomialError("the given basis has repeated monomials")
    return p, exps

"""SOS programs: declare decision variables and constraints; solving is a separate step.

An :class:`SOSProgram` holds declarations only. Every constraint becomes linear equalities
(or inequalities) over decision ids plus PSD cones over Gram blocks (:mod:`.constraints`);
:mod:`.conic` assembles them into one standard-form problem and :mod:`.backends` hands it to
a solver. ``prog.solve()`` returns a :class:`~.solution.Solution` and leaves the program as
it was (it caches its conic form; ``version`` counts declarations, so a Solution knows
whether the program it checks against is still the one it solved).

    p is SOS   <=>   p = z(x)^T Q z(x),  Q >= 0   (coefficient matching: G svec(Q) = coef(p))

Every SOS-type declaration takes ``cone=`` "psd" (default), "sdsos" or "dsos" for its Gram
blocks: inner approximations, valid but weaker bounds (:mod:`.cones`; docs/sos-cones.md).
"""
from __future__ import annotations

import copy
import functools
import time

import numpy as np

from ..errors import InputError, PolynomialError, UnverifiedSolutionError
from ..poly import PolyMatrix, Polynomial, allocate, monomials_up_to, variable_names
from . import conic
from .cones import auxiliary_count, check_cone, cone_rows, face_rows
from .constraints import (Basis, Block, EqualityMultiplier, FamilySOSConstraint, LinearRows, Multiplier,
                          PsdBlock, SOSConstraint, as_sos_polynomial, user_basis,
                          affine_items, affine_rows, gram_polynomial, matrix_form)
from .gram import SQRT2, svec_pairs, svec_size
from .objective import QuadraticForm, is_cvxpy
from .remedies import solve_with_remedies
from .sets import as_set, putinar_terms
from .sparse_constraint import SparseSOSConstraint, local_basis
from .sparsity import clique_vars, constraint_cliques, sparse_bases


class SOSProgram:
    """A sum-of-squares program (see module docstring).

    >>> x, y = variables("x y"); prog = SOSProgram(); g = prog.new_var()
    >>> con = prog.add_sos(x**4 + y**4 - g); prog.maximize(g); sol = prog.solve()
    """

    def __init__(self, name: str = "sos", hint: str | None = None):
        self.name, self.hint = name, hint   # hint: what to try when infeasible, from the program's owner
        self.blocks: list[Block] = []
        self.sos_constraints: list[SOSConstraint] = []
        self.linear: list[LinearRows] = []
        self.cvxpy_constraints: list = []
        self.objective = None          # (sense, expression)
        self.build_seconds = 0.0      # total time spent declaring (all add_* calls)
        self.build_reported = 0.0     # part of it already charged to an earlier Solution
        self._compiled = None          # the conic form, cached until the next change
        self.version = 0              # bumped by every change; a Solution records the one it solved
        self.cvxpy_vars: dict = {}     # one cvxpy Variable per block, made on first use (conic.py)
        self._counter = 0
        self._depth = 0
        self._forms: dict = {}
        self._cone_parts: dict = {}    # id(PsdBlock) -> (auxiliary Block, its rows) of a dsos/sdsos block

    # ------------------------------------------------------------------ naming / caching
    def _name(self, prefix, name):
        self._counter += 1
        return name or f"{prefix}{self._counter}"

    def mark_changed(self):
        """Record a change of the declarations: a new version, the conic form rebuilt on demand."""
        self._compiled = None
        self.version += 1

    def _timed(fn):  # noqa: N805 -- decorator over methods
        @functools.wraps(fn)          # keeps the signature visible (inspect, docs)
        def wrapper(self, *args, **kwargs):
            t0 = time.perf_counter()
            self._depth += 1
            try:
                return fn(self, *args, **kwargs)
            finally:
                self._depth -= 1
                if not self._depth:
                    self.build_seconds += time.perf_counter() - t0
                self.mark_changed()
        return wrapper

    # ------------------------------------------------------------------ decision variables
    def _block(self, name, count, psd_size=None, role="gram") -> Block:
        ids = allocate(count, name)
        psd = PsdBlock(name, ids, psd_size, role=role) if psd_size is not None else None
        block = Block(name, ids, psd)
        self.blocks.append(block)
        return block

    def replace_gram_block(self, psd: PsdBlock, size: int) -> PsdBlock:
        """Swap a Gram block for a new one of another size in the same cone (blocks stay in id order)."""
        aux, rows = self._cone_parts.pop(id(psd), (None, []))
        self.blocks = [b for b in self.blocks if b.psd is not psd and b is not aux]
        self.linear = [r for r in self.linear if not any(r is q for q in rows)]
        new = self._block(psd.name, svec_size(size), size, psd.role).psd
        self._in_cone(new, psd.cone)
        return new

    def _in_cone(self, psd: PsdBlock, cone: str):
        """Put ``psd`` in ``cone``: the auxiliary variables and rows of :func:`.cones.cone_rows`."""
        psd.cone = check_cone(cone)
        if cone == "psd":
            return
        aux = self._block(f"{psd.name}.{'t' if cone == 'dsos' else 'ac'}", auxiliary_count(psd, cone))
        rows = cone_rows(psd, cone, aux.ids)
        self.linear += rows
        self._cone_parts[id(psd)] = (aux, rows)

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
        """Low level: ``count`` free decision variables as ids (for ``Polynomial(vars, exps, coef, ids)``)."""
        return self._block(self._name("ids", name), int(count)).ids

    @_timed
    def new_poly(self, vars, degree: int, min_degree: int = 0, name=None) -> Polynomial:
        """A polynomial in ``vars`` with all monomials of degree in [min_degree, degree] free."""
        names = variable_names(vars)
        exps = monomials_up_to(len(names), degree, min_degree)
        ids = self._block(self._name("poly", name), exps.shape[0]).ids
        return Polynomial(names, exps, np.hstack([np.zeros((len(ids), 1)), np.eye(len(ids))]), ids)

    def _sos_block(self, vars, degree: int, name, role, cone="psd"):
        """(z^T Q z, z, block of Q) for a new Gram block in ``cone``, z all monomials up to degree/2."""
        if degree < 0 or degree % 2:
            raise PolynomialError(f"an SOS polynomial has even degree, got {degree}")
        names = variable_names(vars)
        basis = Basis(names, monomials_up_to(len(names), degree // 2))
        sigma, psd = self._gram(basis, name, role, cone)
        return sigma, basis, psd

    def _gram(self, basis: Basis, name, role, cone):
        """(z^T Q z, block of Q) for a new Gram block over ``basis`` in ``cone``."""
        psd = self._block(name, svec_size(len(basis)), len(basis), role).psd
        self._in_cone(psd, cone)
        return gram_polynomial(basis, psd), psd

    @_timed
    def new_sos(self, vars, degree: int, name=None, cone="psd") -> Polynomial:
        """An SOS polynomial z^T Q z, Q a new Gram block in ``cone``, z all monomials up to degree/2."""
        check_cone(cone)
        return self._sos_block(vars, degree, self._name("sos", name), "sos_var", cone)[0]

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
    def _register(self, name, kind, poly, bases, cone="psd", multipliers=(), source=None, **handles):
        """An SOSConstraint over one block of ``bases`` (:func:`.sparsity.sparse_bases`), else a
        SparseSOSConstraint: the first block the main one, the others "clique" multipliers of 1."""
        vars, mults = poly.vars, list(multipliers)
        main = local_basis(vars, *bases[0], spread=True)
        psd = self._block(name, svec_size(len(main)), len(main)).psd
        self._in_cone(psd, cone)
        for k, (cols, exps) in enumerate(bases[1:], start=1):
            basis = local_basis(vars, cols, exps)
            sigma, block = self._gram(basis, f"{name}.block{k}", "clique", cone)
            mults.append(Multiplier(Polynomial.constant(1.0), sigma, basis, block))
        kind_of = SparseSOSConstraint if len(bases) > 1 or bases[0][0].size != len(vars) else SOSConstraint
        con = kind_of(self, name, kind, poly, main, psd, multipliers=mults, source=source, **handles)
        self.sos_constraints.append(con)
        return con

    @_timed
    def add_sos(self, expr, basis=None, name=None, cone="psd", sparsity=None) -> SOSConstraint:
        """Constrain the polynomial ``expr`` to be a sum of squares.

        Gram basis: from the Newton polytope of ``expr``, or ``basis`` (monomials such as
        ``[1, x, x*y]``, or an exponent array) honoured. ``cone``: "psd", or the inner "sdsos"
        (second-order cones) / "dsos" (an LP) approximations (:mod:`.cones`). ``sparsity``: None
        (one block), "correlative" (one per clique of the variable-interaction graph), "term"
        (one per TSSOS component; splits a given basis too) or "correlative+term" (:mod:`.sparsity`).
        """
        check_cone(cone)
        p = as_sos_polynomial(expr)
        name = self._name("sos", name)
        p, exps = (p, None) if basis is None else user_basis(basis, p)
        return self._register(name, "sos", p, sparse_bases(p.exps, sparsity, dense_basis=exps), cone=cone)

    def _cached_form(self, P: PolyMatrix, taken: tuple) -> Polynomial:
        """y^T P y (y named against ``taken``), expanded once per matrix (families share terms)."""
        key = (id(P), taken)
        if key not in self._forms or self._forms[key][0] is not P:
            self._forms[key] = (P, matrix_form(P, with_basis=False, taken=taken)[0])
        return self._forms[key][1]

    @_timed
    def add_sos_matrix_family(self, terms, weights, name=None, cone="psd") -> "FamilySOSConstraint":
        """sum_t weights[t] * terms[t] is an SOS matrix; the weights can change between solves.

        This is the compile-once path for parametrised problems (cvxpy's Parameters): each
        term is expanded and matched once; ``con.set_weights(w)`` re-solves with new numbers
        at the cost of one dense contraction. The Gram basis covers every term's support.
        ``cone``: the cone of the Gram matrix, as in :meth:`add_sos`.
        """
        check_cone(cone)
        terms = [t if isinstance(t, PolyMatrix) else PolyMatrix(t) for t in terms]
        if not terms or len({t.shape for t in terms}) != 1:
            raise PolynomialError("add_sos_matrix_family needs a non-empty list of equal-shape matrices")
        name = self._name("family", name)
        q0, exps = matrix_form(terms[0], basis_from=terms)
        taken = tuple(sorted({v for t in terms for v in t.vars}))
        qs = [q0] + [self._cached_form(t, taken) for t in terms[1:]]
        psd = self._block(name, svec_size(exps.shape[0]), exps.shape[0]).psd
        self._in_cone(psd, cone)
        vars = qs[0].vars
        con = FamilySOSConstraint(self, name, [q.with_vars(vars) for q in qs], Basis(vars, exps), psd, weights)
        self.sos_constraints.append(con)
        return con

    @_timed
    def add_sos_matrix(self, P, name=None, cone="psd") -> SOSConstraint:
        """Constrain the symmetric polynomial matrix P(x) to be an SOS matrix.

        Equivalent to y^T P(x) y being SOS in (x, y), with the multipartite Gram basis
        y_i * z_i(x), z_i from the Newton polytope of P_ii (never a dense basis in (x, y)).
        A constant P gives a plain LMI P >= 0. ``cone``: the cone of the Gram matrix, as in
        :meth:`add_sos` (for "dsos"/"sdsos" a stronger condition than P being an SOS matrix).
        """
        check_cone(cone)
        name = self._name("sosmat", name)
        q, exps = matrix_form(P)
        return self._register(name, "sos_matrix", q, [(np.arange(q.nvars), exps)], cone=cone)

    @_timed
    def add_nonneg_on(self, expr, ineqs=(), eqs=(), degree=None, name=None, cone="psd",
                      multiplier_cone=None, products=False, sparsity=None) -> SOSConstraint:
        """expr >= 0 on K = {g_i >= 0, h_j = 0}: expr - sum_S sigma_S g_S - sum_j lambda_j h_j SOS.

        ``ineqs``: a :class:`~.sets.BasicSet` or the g_i (``eqs`` the h_j); sigma SOS, lambda free,
        each of the largest degree with deg(multiplier * constraint) <= ``degree`` (one int, or
        a list/dict per constraint, inequalities first); ``products``: True or k adds products of
        up to k inequalities (:mod:`.sets`). ``cone``: of the main block and, unless
        ``multiplier_cone``, the multipliers'. ``sparsity``: as in :meth:`add_sos`; "correlative"
        also puts each multiplier in one clique's variables.
        """
        check_cone(cone)
        multiplier_cone = check_cone(cone if multiplier_cone is None else multiplier_cone, "multiplier_cone")
        p, K = as_sos_polynomial(expr), as_set(ineqs, eqs)
        allv = p.vars + tuple(v for v in K.vars if v not in p.vars)
        terms = putinar_terms(K, degree, products, max([p.degree] + [g.degree for g in K.ineqs + K.eqs]))
        name, source = self._name("nonneg", name), p.with_vars(allv)
        cliques = constraint_cliques(sparsity, allv, source.exps, [g.vars for _, _, g, _ in terms])
        rest, mults, eq_mults = source, [], []
        for kind, label, g, d in terms:
            vars = clique_vars(cliques, g.vars, allv)
            if kind == "sos":
                sigma, basis, psd = self._sos_block(vars, d, f"{name}.{label}", "multiplier", multiplier_cone)
                mults.append(Multiplier(g.with_vars(allv), sigma, basis, psd))
            else:
                sigma = self.new_poly(vars, d, name=f"{name}.{label}")
                eq_mults.append(EqualityMultiplier(g.with_vars(allv), sigma))
            rest = rest - sigma * g
        rest = rest.with_vars(allv)
        return self._register(name, "nonneg_on", rest, sparse_bases(rest.exps, sparsity, cliques=cliques),
                              cone=cone, multipliers=mults, eq_multipliers=eq_mults, source=source)

    @_timed
    def add_eq(self, lhs, rhs=0.0, name=None) -> LinearRows:
        """lhs == rhs, coefficient by coefficient (polynomials or polynomial matrices)."""
        self.linear.append(affine_rows(self._name("eq", name), "eq", affine_items(lhs, rhs)))
        return self.linear[-1]

    @_timed
    def add_ge(self, lhs, rhs=0.0, name=None) -> LinearRows:
        """lhs >= rhs for degree-0 affine expressions (element-wise for matrices)."""
        items = affine_items(lhs, rhs)
        if any(not p.is_constant for p in items):
            raise PolynomialError("add_ge takes constant affine expressions; use add_sos or "
                                  "add_nonneg_on for polynomial inequalities")
        self.linear.append(affine_rows(self._name("ge", name), "ge", items))
        return self.linear[-1]

    def add_constraint(self, constraint):
        """Add a cvxpy constraint written with :meth:`expr`; solves then go through cvxpy."""
        import cvxpy as cp          # lazily: about 3 s to import, only cvxpy interop needs it
        if not isinstance(constraint, cp.constraints.constraint.Constraint):
            raise InputError(f"add_constraint takes a cvxpy constraint, got {type(constraint).__name__}")
        self.cvxpy_constraints.append(constraint)
        self.mark_changed()
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
        self.mark_changed()

    def minimize(self, expr):
        """Minimise an affine scalar, a QuadraticForm (sum_squares) or a cvxpy expression."""
        self._set_objective("min", expr)

    def maximize(self, expr):
        """Maximise an affine scalar or a concave cvxpy expression."""
        self._set_objective("max", expr)

    # ------------------------------------------------------------------ cvxpy interop
    def expr(self, item):
        """The cvxpy expression of a degree-0 affine Polynomial (or PolyMatrix) of this program."""
        return conic.cvxpy_affine(self, item)

    # ------------------------------------------------------------------ solving
    @property
    def ids(self) -> np.ndarray:
        return np.concatenate([b.ids for b in self.blocks] + [np.zeros(0, dtype=np.int64)])

    @property
    def psd_blocks(self) -> list:
        return [b.psd for b in self.blocks if b.psd is not None and b.psd.cone == "psd"]

    def compile(self, scale: bool = True):
        """Assemble (and cache) the standard conic form; see :mod:`sosdyn.sos.conic`."""
        if self._compiled is None or self._compiled.scaled != scale:
            self._compiled = conic.assemble(self, scale=scale)
        return self._compiled

    def tightened(self, kept: dict, margins: dict) -> "SOSProgram":
        """A copy whose Gram blocks are tightened: Q[K, K] >= diag(eps) and Q = 0 outside K.

        ``kept`` maps id(PsdBlock) to the kept indices K (default all), ``margins`` to eps, one
        number or one per kept index (default 0). Each block (in any cone) becomes Q[K, K] = P +
        diag(eps) with P a new block in the same cone; its other rows and columns are fixed to
        zero (the face a solution of this program lies on). Objective, constraints and decision
        ids are shared with this program. Used by proofs (:mod:`.tightened`, :mod:`.rigorous`).
        """
        clone = copy.copy(self)
        clone.name = f"{self.name} (tightened)"
        clone.blocks = [Block(b.name, b.ids) if b.psd is not None and b.psd.cone == "psd" else b
                        for b in self.blocks]
        clone.linear, clone.sos_constraints = list(self.linear), list(self.sos_constraints)
        clone._compiled, clone._forms = None, {}
        clone.cvxpy_vars = dict(self.cvxpy_vars)    # the same variables: a cvxpy objective still reads them
        clone._cone_parts = dict(self._cone_parts)
        for b in self.blocks:
            if b.psd is None or not b.psd.size:
                continue
            K = np.asarray(kept.get(id(b.psd), np.arange(b.psd.size)), dtype=np.int64)
            inner = None
            if K.size:
                inner = clone._block(f"{b.name}.interior", svec_size(K.size), K.size, b.psd.role).psd
                clone._in_cone(inner, b.psd.cone)
            rows = face_rows(b.psd, K, inner, margins.get(id(b.psd), 0.0))
            clone.linear += rows
        return clone

    def solve(self, solver: str = "CLARABEL", backend: str = "auto", scale: bool = True,
              verbose: bool = False, raise_on_failure: bool = False, rigorous: bool = False,
              retry: bool = True, prove: bool = True, **settings):
        """Solve and return a :class:`~sosdyn.sos.solution.Solution`.

        ``backend``: "direct" hands the conic data straight to Clarabel (no canonicalisation: the fast
        re-solve path); "cvxpy" goes through cvxpy (any cvxpy solver; needed for cvxpy constraints and
        objectives); "auto" picks direct when it can. ``raise_on_failure``: raise SolverError /
        InfeasibleError / UnverifiedSolutionError instead of returning an unverified Solution.
        ``rigorous``: every number is read where the whole certificate holds exactly (``sol.bound``
        compares the proven bound with the solver's; :mod:`.rigorous`). ``retry``: re-solve with other
        settings after a numerical failure; after "unbounded", check the constraints alone (:mod:`.remedies`).
        ``prove``: run the proof's remedies that need no re-solve now (:mod:`.proven`; False for a
        program solved only for its numbers, as the proof's own re-solves are).
        """
        sol = solve_with_remedies(self, solver, backend, scale, verbose, self.build_seconds - self.build_reported,
                                  settings, retry)
        self.build_reported = self.build_seconds
        sol.rigorous = rigorous
        sol.verify()                        # now, while the program is the one that was solved
        if prove:
            sol.settle()                    # and the proof's remedies that need no re-solve
        if rigorous and sol.verified:
            try:
                sol.rigorous_bound()        # now, so its time is in sol.timings["rigorous"]
            except UnverifiedSolutionError:
                pass                        # raised again, with its reason, when a number is asked for
        if raise_on_failure:
            sol.raise_for_status()
        return sol

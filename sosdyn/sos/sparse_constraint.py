"""A sparse SOS constraint: p = sum_k z_k^T Q_k z_k over Gram blocks in few variables each.

``add_sos(..., sparsity=...)`` (and ``add_nonneg_on``) give one Gram block per clique or
term component (:mod:`.sparsity`). Each block's basis z_k is kept over its own variables
only, and the coefficient matching

    coef(p) = sum_k G_k svec(Q_k)      (one row per monomial of p or of some z_k z_k^T)

is assembled once, from arrays: every monomial is written as the sorted multiset of its
variables' indices (x1^2 x3 -> (1, 1, 3), padded with 0 to the largest degree;
:func:`multiset_keys`), so monomials from different blocks meet in one small table whose
width is the degree, not the number of variables. No polynomial p - sum_k sigma_k (whose
coefficient array would be monomials x all decision variables) is formed; the work and
memory grow linearly with the number of blocks. :attr:`SparseSOSConstraint.poly` still
gives that polynomial, built on demand (rigorous proofs, a user's inspection).

The independent check (:func:`.verification.check_blocks_values`) reads the same identity
from :meth:`SparseSOSConstraint.identity_values`: p at the decision values, every block's
full product table z_k z_k^T (not the svec matching above), the Q_k.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..poly import Polynomial, keys_to_exps, multiset_keys, unique_rows
from .constraints import Basis, LinearRows, SOSConstraint, as_sos_polynomial
from .gram import gram_matching, svec_to_matrix
from .verification import GramStructure


class SparseSOSConstraint(SOSConstraint):
    """"p is SOS" with several Gram blocks (module docstring).

    ``p`` is the polynomial the blocks must sum to (``source`` for add_sos; source minus the
    multiplier terms for add_nonneg_on); ``basis``/``psd`` the first block (over all the
    constraint's variables), the others are the "clique" multipliers of the constant 1, each
    with a basis over its own variables.
    """

    def __init__(self, program, name, kind, p, basis, psd, multipliers=(), eq_multipliers=(), source=None):
        self.program, self.name, self.kind = program, name, kind
        self.basis, self.psd = basis, psd
        self.multipliers, self.eq_multipliers = list(multipliers), list(eq_multipliers)
        self.p: Polynomial = p.with_vars(basis.vars)
        self.source: Polynomial = self.p if source is None else source.with_vars(basis.vars)
        where = {v: i for i, v in enumerate(basis.vars)}
        self._cols = [np.array([where[v] for v in b.vars], dtype=np.int64) for b, _ in self.gram_blocks]
        self._width = max([int(b.exps.sum(axis=1).max(initial=0)) * 2 for b, _ in self.gram_blocks]
                          + [int(self.p.exps.sum(axis=1).max(initial=0))])
        self._poly = self._structure = None
        self.rows: LinearRows | None = None
        self.infeasible_reason: str | None = None
        self._match()

    @property
    def poly(self) -> Polynomial:
        """p - sum_k sigma_k over the clique blocks, as one decision polynomial (made on demand)."""
        if self._poly is None:
            rest = self.p
            for m in self.multipliers:
                if m.psd.role == "clique":
                    rest = rest - m.poly.with_vars(self.basis.vars)
            self._poly = rest
        return self._poly

    def _match(self):
        """coef(p) = sum_k G_k svec(Q_k): one block of sparse rows over the union U of monomials."""
        p, width = self.p, self._width
        matched = [gram_matching(b.exps) for b, _ in self.gram_blocks]
        keys = [multiset_keys(p.exps, np.arange(p.nvars), width)]
        keys += [multiset_keys(exps, cols, width) for (exps, _, _), cols in zip(matched, self._cols)]
        U, inv = unique_rows(np.vstack(keys))
        starts = np.cumsum([0] + [k.shape[0] for k in keys])
        idx_p = inv[:starts[1]]
        prows = LinearRows.from_affine(self.name, "eq", p.coef, p.ids, idx_p)
        rhs = np.zeros(U.shape[0])
        rhs[idx_p] = p.coef[:, 0]
        g_rows = [inv[starts[k + 1]:starts[k + 2]][rows] for k, (_, rows, _) in enumerate(matched)]
        self.rows = LinearRows(
            self.name, "eq",
            np.concatenate([prows.rows] + g_rows),
            np.concatenate([prows.ids] + [psd.ids for _, psd in self.gram_blocks]),
            np.concatenate([-prows.vals] + [w for _, _, w in matched]),
            rhs)
        covered = np.zeros(U.shape[0], dtype=bool)
        covered[inv[starts[1]:]] = covered[prows.rows] = True
        bad = np.flatnonzero(~covered & (rhs != 0))
        self.infeasible_reason = None if not bad.size else (
            f"constraint {self.name!r}: monomial "
            f"{Polynomial(self.basis.vars, keys_to_exps(U[bad[:1]], p.nvars), [1.0])!r} has a fixed "
            f"non-zero coefficient but cannot be produced by any of its {len(self.gram_blocks)} Gram blocks")

    def identity_structure(self) -> GramStructure:
        """Where p's monomials and every block's products z_i z_j (all b_k^2 of them, blocks in
        order) land in their union; ``first_block[u]`` the first block producing u (-1: none)."""
        if self._structure is None:
            width = self._width
            keys = [multiset_keys(self.p.exps, np.arange(self.p.nvars), width)]
            for (b, _), cols in zip(self.gram_blocks, self._cols):
                pairs = (b.exps[:, None, :] + b.exps[None, :, :]).reshape(-1, b.exps.shape[1])
                keys.append(multiset_keys(pairs, cols, width))
            _, inv = unique_rows(np.vstack(keys))
            size = int(inv.max(initial=-1)) + 1
            first = np.full(size, -1, dtype=np.int64)
            owner = np.repeat(np.arange(len(keys) - 1), [k.shape[0] for k in keys[1:]])
            at = inv[keys[0].shape[0]:]
            first[at[::-1]] = owner[::-1]                    # the last write is the first block
            in_gram = first >= 0
            self._structure = GramStructure(inv[:keys[0].shape[0]], at, in_gram, first)
        return self._structure

    def identity_values(self, at):
        """(p's coefficients at the decision values, :meth:`identity_structure`, the blocks' Q_k,
        their cones); ``at(ids)`` gives the values of decision ids."""
        p = self.p
        coef = p.coef[:, 0] + p.coef[:, 1:] @ at(p.ids)
        Qs = [svec_to_matrix(at(psd.ids), psd.size) for _, psd in self.gram_blocks]
        return coef, self.identity_structure(), Qs, [psd.cone for _, psd in self.gram_blocks]

    def update(self, poly) -> "SparseSOSConstraint":
        """New numbers for the source polynomial, the same Gram blocks (re-matched, no new basis:
        a monomial no block produces makes the program infeasible, with that reason)."""
        source = as_sos_polynomial(poly)
        if not set(source.vars) <= set(self.basis.vars):
            raise InputError(f"constraint {self.name!r}: the new polynomial has variables "
                             f"{sorted(set(source.vars) - set(self.basis.vars))} the sparse Gram blocks do not "
                             "cover. Try: add a new constraint for it")
        p = source
        for m in self.multipliers + self.eq_multipliers:
            if not (hasattr(m, "psd") and m.psd.role == "clique"):
                p = p - m.poly * m.constraint
        self.p, self.source = p.with_vars(self.basis.vars), source.with_vars(self.basis.vars)
        self._width = max(self._width, int(self.p.exps.sum(axis=1).max(initial=0)))
        self._poly = self._structure = None
        self._match()
        self.program.mark_changed()
        return self


def local_basis(vars: tuple, cols: np.ndarray, exps: np.ndarray, spread: bool = False) -> Basis:
    """The basis of exponent rows ``exps`` over the variables ``vars[cols]``; with ``spread``,
    the same monomials over all of ``vars`` (zero exponents outside ``cols``)."""
    if not spread:
        return Basis(tuple(vars[c] for c in cols), exps)
    full = np.zeros((exps.shape[0], len(vars)), dtype=np.int64)
    full[:, cols] = exps
    return Basis(tuple(vars), full)

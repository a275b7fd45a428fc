"""Sparse Gram bases: one Gram block per clique (correlative) or per term component (TSSOS).

A sparse polynomial is often SOS with a block-diagonal Gram matrix; every block-diagonal
restriction is still a valid certificate (p = sum_k z_k^T Q_k z_k, Q_k >= 0), only possibly
a weaker one, and the blocks are much smaller than one dense Gram matrix.

* correlative sparsity (Waki, Kim, Kojima & Muramatsu 2006): the variable-interaction graph
  links x_i and x_j when some term of p (or one constraint g) contains both. A chordal
  extension (greedy minimum-degree elimination) has maximal cliques C_1..C_m; block k holds
  the monomials in the variables of C_k only. Since the exponents are >= 0, the points of
  N(p) with zero exponents outside C form a face of N(p), the hull of the support terms in
  the variables of C; so the Newton-polytope test for a candidate a with supp(a) in C runs
  in |C| dimensions (:func:`clique_bases`).
* term sparsity (TSSOS, Wang, Magron & Lasserre 2021): on a basis b_1..b_s the graph links
  b_i and b_j when b_i + b_j is in supp(p) or is an even square 2 b_k; its connected
  components are the blocks. The support is then extended by every b_i + b_j inside a
  block and the graph rebuilt, until the components stop merging (:func:`term_blocks`).
* "correlative+term": term sparsity inside each clique's basis.

Functions on arrays; :func:`sparse_bases` is what ``SOSProgram.add_sos(..., sparsity=)`` calls.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import InputError
from ..limits import check_bytes
from ..poly.monomials import match_rows, monomials_up_to, unique_rows
from .newton import gram_matching_bytes, in_hull, newton_basis

SPARSITY = (None, "correlative", "term", "correlative+term")
SPARSITY_HINT = "Try: sparsity=None (dense), 'correlative', 'term' or 'correlative+term'"


def check_sparsity(sparsity):
    """``sparsity`` if it is one of :data:`SPARSITY`; InputError otherwise."""
    if sparsity not in SPARSITY:
        raise InputError(f"unknown sparsity {sparsity!r}. {SPARSITY_HINT}")
    return sparsity


def interaction_graph(n: int, support: np.ndarray, groups=()) -> list:
    """Adjacency sets of the variable-interaction graph: i ~ j when a term of ``support``
    (exponent rows over n variables) or a variable group (index lists) holds both."""
    adj = [set() for _ in range(n)]
    members = [np.flatnonzero(row) for row in unique_rows((support > 0).astype(np.int64))[0]]
    for idx in members + [np.asarray(g, dtype=np.int64) for g in groups]:
        for i in idx:
            adj[i].update(int(j) for j in idx if j != i)
    return adj


def chordal_cliques(adj: list) -> list:
    """Maximal cliques (sorted index arrays) of a chordal extension of the graph ``adj``.

    Greedy minimum-degree elimination: eliminating v adds fill edges between its remaining
    neighbours, so {v} + those neighbours is a clique of the extension; the maximal ones
    among them are all its maximal cliques (every clique of a chordal graph appears so).
    """
    nbrs = [set(a) for a in adj]
    alive = set(range(len(adj)))
    cliques: list = []
    while alive:
        v = min(alive, key=lambda u: (len(nbrs[u]), u))
        clique = frozenset(nbrs[v] | {v})
        for u in nbrs[v]:
            nbrs[u] |= nbrs[v] - {u}
            nbrs[u].discard(v)
        alive.discard(v)
        if not any(clique <= c for c in cliques):
            cliques.append(clique)
    return [np.array(sorted(c), dtype=np.int64) for c in cliques]


def constraint_cliques(sparsity, allv: tuple, support: np.ndarray, groups: list):
    """The cliques (index arrays into ``allv``) of a constrained "correlative" problem, else None:
    the interaction graph of ``support`` with every group of variable names made a clique."""
    if check_sparsity(sparsity) not in ("correlative", "correlative+term"):
        return None
    idx = [[allv.index(v) for v in names] for names in groups]
    return chordal_cliques(interaction_graph(len(allv), support, idx))


def clique_vars(cliques, names, allv: tuple) -> tuple:
    """The variables of the first clique holding all of ``names`` (all of ``allv`` if no cliques)."""
    if cliques is None:
        return allv
    idx = {allv.index(v) for v in names}
    return tuple(allv[i] for i in next(C for C in cliques if idx <= set(C.tolist())))


def clique_bases(support: np.ndarray, cliques: list) -> list:
    """Per clique C, the half-degree monomials a with supp(a) in C and 2a in N(support).

    The test runs on the face of N(support) with zero exponents outside C (module docstring).
    """
    n = support.shape[1]
    deg = support.sum(axis=1)
    lo, hi = int(np.ceil(deg.min() / 2)), int(deg.max() // 2)
    out = []
    for C in cliques:
        outside = np.setdiff1d(np.arange(n), C)
        face = support[(support[:, outside] == 0).all(axis=1)][:, C]
        basis = np.zeros((0, n), dtype=np.int64)
        if face.shape[0]:
            cand = monomials_up_to(C.size, hi, lo, max_per_var=face.max(axis=0) // 2)
            cand = cand[(2 * cand >= face.min(axis=0)).all(axis=1)]
            cand = cand[in_hull(2 * cand, face)] if cand.shape[0] else cand
            basis = np.zeros((cand.shape[0], n), dtype=np.int64)
            basis[:, C] = cand
        out.append(basis)
    return out


def term_blocks(support: np.ndarray, basis: np.ndarray) -> list:
    """Index arrays into ``basis``: the TSSOS blocks (module docstring), iterated to a fixed point."""
    s = basis.shape[0]
    if s == 0:
        return []
    i, j = np.triu_indices(s)
    sums = basis[i] + basis[j]
    known = unique_rows(np.vstack([support, 2 * basis]))[0]
    labels = np.zeros(s, dtype=np.int64)
    count = -1
    while True:
        linked = match_rows(known, sums) >= 0
        graph = coo_matrix((np.ones(int(linked.sum())), (i[linked], j[linked])), shape=(s, s))
        new_count, labels = connected_components(graph, directed=False)
        if new_count == count:
            break
        count = new_count
        same = labels[i] == labels[j]
        known = unique_rows(np.vstack([known, sums[same]]))[0]
    return [np.flatnonzero(labels == k) for k in range(count)]


def sparse_bases(support: np.ndarray, sparsity, dense_basis=None, cliques=None) -> list:
    """The Gram blocks' bases (exponent arrays over the support's variables) for ``sparsity``.

    ``dense_basis``: the basis "term" splits (default the Newton basis of ``support``);
    ``cliques``: the variable cliques of "correlative" (default those of ``support``'s
    interaction graph). The total coefficient-matching memory of the blocks is checked
    against the limits.
    """
    n = support.shape[1]
    if check_sparsity(sparsity) in ("correlative", "correlative+term"):
        if dense_basis is not None:
            raise InputError("a given basis= is split by sparsity='term' only. Try: basis=None with "
                             "sparsity='correlative', or sparsity='term' with your basis")
        if cliques is None:
            cliques = chordal_cliques(interaction_graph(n, support))
        bases = clique_bases(support, cliques)
    else:
        bases = [newton_basis(support) if dense_basis is None else dense_basis]
    if sparsity is None:
        return bases
    if sparsity in ("term", "correlative+term"):
        bases = [b[k] for b in bases for k in term_blocks(support, b)]
    bases = [b for b in bases if b.shape[0]]
    check_bytes(sum(gram_matching_bytes(b.shape[0], n) for b in bases),
                f"coefficient matching over {len(bases)} Gram blocks of sizes "
                f"{sorted((b.shape[0] for b in bases), reverse=True)[:5]}... in {n} variables",
                "lower the degree, or use sparsity='correlative+term'")
    return bases or [np.zeros((0, n), dtype=np.int64)]

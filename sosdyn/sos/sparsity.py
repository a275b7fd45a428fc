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

import heapq

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


def term_variables(support: np.ndarray) -> list:
    """The variable indices of each term of ``support`` with a variable (one index array per term)."""
    r, c = np.nonzero(support)
    return np.split(c, np.flatnonzero(np.diff(r)) + 1) if r.size else []


def interaction_graph(n: int, support: np.ndarray, groups=()) -> list:
    """Adjacency sets of the variable-interaction graph: i ~ j when a term of ``support``
    (exponent rows over n variables) or a variable group (index lists) holds both."""
    adj = [set() for _ in range(n)]
    for idx in term_variables(support) + [np.asarray(g, dtype=np.int64) for g in groups]:
        idx = idx.tolist()
        for i in idx:
            adj[i].update(j for j in idx if j != i)
    return adj


def min_degree_elimination(adj: list):
    """Greedy minimum-degree elimination of the graph ``adj`` (adjacency sets; not changed):
    yields (v, its neighbours when eliminated) in turn. Eliminating v adds fill edges between
    those neighbours. A heap keyed by (degree, vertex) picks v, stale entries skipped."""
    nbrs = [set(a) for a in adj]
    heap = [(len(a), v) for v, a in enumerate(nbrs)]
    heapq.heapify(heap)
    alive = np.ones(len(adj), dtype=bool)
    while heap:
        deg, v = heapq.heappop(heap)
        if not alive[v] or deg != len(nbrs[v]):
            continue
        for u in nbrs[v]:
            nbrs[u] |= nbrs[v] - {u}
            nbrs[u].discard(v)
            heapq.heappush(heap, (len(nbrs[u]), u))
        alive[v] = False
        yield v, nbrs[v]


def chordal_cliques(adj: list) -> list:
    """Maximal cliques (sorted index arrays) of a chordal extension of the graph ``adj``.

    Greedy minimum-degree elimination (:func:`min_degree_elimination`): {v} + v's neighbours
    when eliminated is a clique of the extension; the maximal ones among them are all its
    maximal cliques (every clique of a chordal graph appears so). A candidate is compared
    only with the kept cliques that hold its vertex of least index, so the work grows with
    the edges of the extension, not with the square of the vertex count.
    """
    cliques: list = []
    holding: dict = {}                      # vertex -> indices of kept cliques holding it
    for v, nb in min_degree_elimination(adj):
        clique = frozenset(nb | {v})
        if not any(clique <= cliques[k] for k in holding.get(min(clique), ())):
            for u in clique:
                holding.setdefault(u, []).append(len(cliques))
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


def clique_faces(support: np.ndarray, cliques: list) -> list:
    """Per clique C, the terms of ``support`` whose variables all lie in C, on C's columns.

    A term is looked up from the clique holding its variable of least index only through the
    cliques of that variable (an index from variable to cliques), so the work is linear in
    the terms and the clique sizes, never terms x variables x cliques.
    """
    holding: dict = {}
    for k, C in enumerate(cliques):
        for v in C.tolist():
            holding.setdefault(v, []).append(k)
    rows: list = [[] for _ in cliques]
    nz_r, nz_c = np.nonzero(support)
    starts = np.concatenate(([0], np.cumsum(np.bincount(nz_r, minlength=support.shape[0]))))
    sets = [frozenset(C.tolist()) for C in cliques]
    for t in range(support.shape[0]):
        cols = nz_c[starts[t]:starts[t + 1]].tolist()
        for k in (holding.get(cols[0], ()) if cols else range(len(cliques))):
            if all(c in sets[k] for c in cols):
                rows[k].append(t)
    return [support[np.asarray(r, dtype=np.int64)][:, C] for r, C in zip(rows, cliques)]


def clique_bases(support: np.ndarray, cliques: list) -> list:
    """Per clique C, the half-degree monomials a with supp(a) in C and 2a in N(support), as
    exponent rows over C's variables only (the columns C of ``support``).

    The test runs on the face of N(support) with zero exponents outside C (module docstring).
    """
    deg = support.sum(axis=1)
    lo, hi = int(np.ceil(deg.min() / 2)), int(deg.max() // 2)
    out, memo = [], {}            # a chain repeats its faces (in clique coordinates): each is solved once
    for C, face in zip(cliques, clique_faces(support, cliques)):
        key = (face.shape, face.tobytes())
        if key not in memo:
            basis = np.zeros((0, C.size), dtype=np.int64)
            if face.shape[0]:
                cand = monomials_up_to(C.size, hi, lo, max_per_var=face.max(axis=0) // 2)
                cand = cand[(2 * cand >= face.min(axis=0)).all(axis=1)]
                basis = cand[in_hull(2 * cand, face)] if cand.shape[0] else cand
            memo[key] = basis
        out.append(memo[key])
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
    """The Gram blocks' bases for ``sparsity``: (variable indices into the support's columns,
    exponent rows over those variables) per block; one block over every variable if dense.

    ``dense_basis``: the basis "term" splits (default the Newton basis of ``support``);
    ``cliques``: the variable cliques of "correlative" (default those of ``support``'s
    interaction graph). Term sparsity inside a clique uses the clique's face of the support
    (its terms in the clique's variables). The total coefficient-matching memory of the blocks
    is checked against the limits.
    """
    n = support.shape[1]
    if check_sparsity(sparsity) in ("correlative", "correlative+term"):
        if dense_basis is not None:
            raise InputError("a given basis= is split by sparsity='term' only. Try: basis=None with "
                             "sparsity='correlative', or sparsity='term' with your basis")
        if cliques is None:
            cliques = chordal_cliques(interaction_graph(n, support))
        faces = clique_faces(support, cliques) if sparsity == "correlative+term" else [None] * len(cliques)
        blocks = list(zip(cliques, clique_bases(support, cliques), faces))
    else:
        basis = newton_basis(support) if dense_basis is None else dense_basis
        blocks = [(np.arange(n, dtype=np.int64), basis, support)]
    if sparsity is None:
        return [(C, b) for C, b, _ in blocks]
    if sparsity in ("term", "correlative+term"):
        blocks = [(C, b[k], face) for C, b, face in blocks for k in term_blocks(face, b)]
    blocks = [(C, b) for C, b, _ in blocks if b.shape[0]]
    check_bytes(sum(gram_matching_bytes(b.shape[0], C.size) for C, b in blocks),
                f"coefficient matching over {len(blocks)} Gram blocks of sizes "
                f"{sorted((b.shape[0] for _, b in blocks), reverse=True)[:5]}... in {n} variables",
                "lower the degree, or use sparsity='correlative+term'")
    return blocks or [(np.arange(n, dtype=np.int64), np.zeros((0, n), dtype=np.int64))]

"""The fill of an interior-point solver's KKT factor, for the memory estimate of a solve.

Clarabel factors (LDL^T) a KKT matrix over the variables and the constraint rows in which a
PSD cone of svec size s is a dense s x s block. Group the columns of the constraint matrix A
(equalities, inequalities, second-order cone rows): each PSD block's svec entries are one
group, every other variable a group of its own. Eliminating a group g of s_g columns that
touch the rows R_g costs a dense s_g x s_g factor block and s_g x |R_g| entries to its rows,
and leaves the rows R_g linked to each other (a clique in the *row graph*). The rows are then
eliminated in greedy minimum-degree order (:func:`.sparsity.min_degree_elimination`, the
ordering family of the solver's AMD), each costing one entry per neighbour left. So

    F = sum_PSD s_g (s_g + 1) / 2 + sum_g s_g |R_g| + sum_rows (degree at elimination + 1).

For a single dense block over m rows this is (s + m)(s + m + 1) / 2, the dense group the
estimate was calibrated on; on a chain of small blocks (correlative sparsity) every term is
local and F grows linearly with the chain. When the row graph has more than a quarter of all
possible edges it is counted dense (m (m + 1) / 2) without running the elimination, and an
elimination that has spent ``ELIMINATION_WORK`` set updates counts the rows it has not reached
as dense (an upper bound of any continuation): the estimate stays fast on every program.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .sparsity import min_degree_elimination

DENSE_ROW_GRAPH = 0.25     # edge share above which the row graph is counted dense
ELIMINATION_WORK = 2e7     # set updates the elimination may spend (sum of degree^2) before the
                           # rows left are counted dense


def column_groups(data) -> tuple:
    """(group of every variable, svec size of every group, which groups are PSD blocks)."""
    group = np.full(data.n, -1, dtype=np.int64)
    for k, (pos, _) in enumerate(data.psd):
        group[pos] = k
    free = group < 0
    group[free] = len(data.psd) + np.arange(int(free.sum()))
    size = np.bincount(group, minlength=len(data.psd) + int(free.sum())).astype(float)
    return group, size, np.arange(size.size) < len(data.psd)


def factor_entries(data) -> float:
    """F of the module docstring for :class:`~.conic.ConicData`."""
    parts = [data.A_eq, data.A_ge] + ([data.soc] if data.soc is not None else [])
    A = sp.vstack([sp.csr_matrix(M) for M in parts]).tocoo()
    m = A.shape[0]
    group, size, psd = column_groups(data)
    pairs = np.unique(np.stack([group[A.col], A.row], axis=1), axis=0) if A.nnz else np.zeros((0, 2), np.int64)
    touched = np.bincount(pairs[:, 0], minlength=size.size).astype(float)
    groups = (size[psd] * (size[psd] + 1) / 2).sum() + (size * touched).sum()
    split = np.flatnonzero(np.diff(pairs[:, 0])) + 1
    row_sets = [r for r in np.split(pairs[:, 1], split) if r.size > 1]
    edges = sum(r.size * (r.size - 1) / 2 for r in row_sets)
    if edges > DENSE_ROW_GRAPH * m * (m - 1) / 2:
        return float(groups + m * (m + 1) / 2)
    adj = [set() for _ in range(m)]
    for rows in row_sets:
        rows = rows.tolist()
        for r in rows:
            adj[r].update(rows)
    for r in range(m):
        adj[r].discard(r)
    rows, work, left = 0.0, 0.0, m
    for _, nb in min_degree_elimination(adj):
        rows, work, left = rows + len(nb) + 1, work + len(nb) ** 2, left - 1
        if work > ELIMINATION_WORK:           # the rest at most dense: left (left + 1) / 2 entries
            return float(groups + rows + left * (left + 1) / 2)
    return float(groups + rows)

"""The sparse build (sosdyn.sos.sparse_constraint): multiset monomial keys, matching assembled once,
the same rows as the polynomial route, linear growth, update; known answers."""

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos.constraints import gram_polynomial
from sosdyn.sos.gram import gram_matching
from sosdyn.poly import keys_to_exps, multiset_keys
from sosdyn.sos.sparse_constraint import SparseSOSConstraint
from sosdyn.sos.sparsity import clique_faces, sparse_bases


def wood(n):
    """Chained Wood (minimum 1 at x = 1), its brackets summed pairwise (a chain of n additions
    over all the variables so far would be quadratic)."""
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    parts = [100 * (b - a**2) ** 2 + (1 - a) ** 2 + 90 * (d - c**2) ** 2 + (1 - c) ** 2
             + 10 * (b + d - 2) ** 2 + 0.1 * (b - d) ** 2 for a, b, c, d in (xs[i:i + 4] for i in range(0, n - 3, 2))]
    while len(parts) > 1:
        parts = [sum(parts[k:k + 2]) for k in range(0, len(parts), 2)]
    return 1 + parts[0]


def test_multiset_keys_name_a_monomial_by_its_variables():
    # x1^2 x3 over columns (1, 3, 7) of a wider vector: indices 1, 1, 3 -> keys 2, 2, 4 (+1, zero pad)
    exps = np.array([[2, 1, 0], [0, 0, 1], [0, 0, 0]])
    keys = multiset_keys(exps, np.array([1, 3, 7]), 4)
    assert keys.tolist() == [[2, 2, 4, 0], [8, 0, 0, 0], [0, 0, 0, 0]]
    assert keys_to_exps(keys, 8)[0].tolist() == [0, 2, 0, 1, 0, 0, 0, 0]


def test_clique_faces_hold_the_terms_inside_each_clique():
    # terms x0^2, x0 x1, x1 x2, x2^2 over cliques {0, 1}, {1, 2}: the face of {1, 2} has no x0 term
    support = np.array([[2, 0, 0], [1, 1, 0], [0, 1, 1], [0, 0, 2]])
    faces = clique_faces(support, [np.array([0, 1]), np.array([1, 2])])
    assert faces[0].tolist() == [[2, 0], [1, 1]] and faces[1].tolist() == [[1, 1], [0, 2]]


def test_sparse_rows_equal_the_rows_of_the_polynomial_route():
    # the matching over multiset keys gives the same equations as the polynomial
    # p - sum_k z_k^T Q_k z_k (all blocks, the first included) made by polynomial arithmetic
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(wood(8) - g, sparsity="correlative")
    assert isinstance(con, SparseSOSConstraint) and len(con.gram_blocks) == 7
    poly = (con.poly - gram_polynomial(con.basis, con.psd)).with_vars(con.basis.vars)
    keys = multiset_keys(poly.exps, np.arange(poly.nvars), con._width)
    A = np.zeros((con.rows.rhs.size, 1 + int(max(con.rows.ids.max(), poly.ids.max())) + 1))
    np.add.at(A, (con.rows.rows, 1 + con.rows.ids), con.rows.vals)
    A[:, 0] = -con.rows.rhs
    U = {tuple(k): r for r, k in enumerate(_row_keys(con))}
    for k, row in zip(keys, poly.coef):                # each monomial's equation: coef(poly) = 0
        r = U[tuple(k)]
        want = np.zeros(A.shape[1])
        want[0] = row[0]
        want[1 + poly.ids] = row[1:]
        np.testing.assert_allclose(-A[r], want, atol=1e-12)


def _row_keys(con):
    """The multiset key of every matching row of ``con`` (rows are the sorted union of keys)."""
    p = con.p
    keys = [multiset_keys(p.exps, np.arange(p.nvars), con._width)]
    keys += [multiset_keys(gram_matching(b.exps)[0], cols, con._width)
             for (b, _), cols in zip(con.gram_blocks, con._cols)]
    return np.unique(np.vstack(keys), axis=0)


def test_chained_wood_correlative_bound_is_one():
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(wood(40) - g, sparsity="correlative")
    prog.maximize(g)
    sol = prog.solve()
    assert sol.value(g) == pytest.approx(1.0, abs=1e-5)
    assert all(len(b.vars) <= 3 for b, _ in con.gram_blocks[1:])      # blocks in their clique's variables
    assert len(con.gram_blocks) == 39


def test_sparse_lower_bound_is_made_safe_block_by_block():
    """The solver's gamma for chained Wood (min 1 at x = 1) lies above the minimum; ``objective``
    lowers it by sum_k delta_k over the clique blocks (posterior.block_shift) to a true bound."""
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(wood(40) - g, sparsity="correlative")
    prog.maximize(g)
    sol = prog.solve()
    assert 1.0 - 1e-4 <= sol.objective <= 1.0                         # the returned one is, and tight


def test_update_keeps_the_blocks_and_rematches():
    x, y, z = sd.variables("x y z")
    prog = sd.SOSProgram()
    g = prog.new_var()
    # x^2 + z^2 make the quadratic part definite (min 3 / 5 at 0, Gram blocks nonsingular off the
    # constant, so the bound is corrected, not refused; (x - y)^2 + (y - z)^2 alone vanishes on a
    # line and its clique blocks are forced singular: see test_safe_bounds)
    f = (x - y) ** 2 + (y - z) ** 2 + x**2 + z**2
    con = prog.add_sos(f + 3 - g, sparsity="correlative")
    prog.maximize(g)
    assert 3.0 - 1e-6 <= prog.solve().value(g) <= 3.0
    blocks = [psd.name for _, psd in con.gram_blocks]
    con.update(f + 5 - g)
    assert 5.0 - 1e-6 <= prog.solve().value(g) <= 5.0
    assert [psd.name for _, psd in con.gram_blocks] == blocks
    with pytest.raises(sd.InputError, match="do not cover"):
        con.update((x - sd.variables("w")[0]) ** 2 - g)


def test_sparse_bases_stay_in_the_clique_variables():
    support = wood(200).exps
    bases = sparse_bases(support, "correlative")
    assert len(bases) == 199 and all(cols.size <= 3 and b.shape[1] == cols.size for cols, b in bases)


@pytest.mark.slow
def test_chained_wood_400_is_bounded_by_its_cliques():
    # issue 27's speed targets (build + solve <= 10 s, build(400) <= 15 x build(40)) are measured by
    # `make bench-sos` (problems.bench.sparse_scaling); here: the bound (minimum 1), from 399 blocks
    # of at most 3 variables each
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(wood(400) - g, sparsity="correlative")
    prog.maximize(g)
    assert len(con.gram_blocks) == 399 and all(len(b.vars) <= 3 for b, _ in con.gram_blocks[1:])
    assert 1.0 - 1e-4 <= prog.solve().value(g) <= 1.0

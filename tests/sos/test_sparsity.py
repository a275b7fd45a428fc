"""Sparse Gram bases: correlative cliques and TSSOS term blocks, with known answers.

Chained Rosenbrock f = sum_i 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2 is a sum of squares with
minimum 0 at (1, ..., 1), so max g with f - g SOS is 0 exactly; its interaction graph is a
path, so the cliques are the n - 1 pairs {x_i, x_{i+1}}.
"""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import BasicSet, minimize_on
from sosdyn.sos.conic import positions
from sosdyn.sos.gram import matrix_to_svec
from sosdyn.sos.sparsity import (
    chordal_cliques,
    interaction_graph,
    sparse_bases,
    term_blocks,
)


def rosenbrock(n):
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    return sum(100 * (xs[i + 1] - xs[i] ** 2) ** 2 + (1 - xs[i]) ** 2 for i in range(n - 1))


def block_variables(con):
    """The number of variables each Gram block's monomials use."""
    return [int((b.exps.sum(axis=0) > 0).sum()) for b, _ in con.gram_blocks]


@pytest.mark.parametrize("n", [6, 8, 10, 20])
def test_chained_rosenbrock_correlative_bound_is_zero(n):
    # sum 100 (x_(i+1) - x_i^2)^2 + (1 - x_i)^2: a sum of squares, minimum 0 at x = 1, each clique's
    # block singular along z(1) and the last along x_n - x_(n-1)^2 in every exact certificate (no
    # interior, no floating-point margin): the face the solver's kernel names carries the proof
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(rosenbrock(n) - g, sparsity="correlative")
    prog.maximize(g)
    sol = prog.solve()
    assert -1e-6 <= sol.value(g) <= 0.0
    assert block_variables(con) == [2] * (n - 1)                     # n - 1 cliques of size 2
    # clique {x_i, x_i+1}: 1, x_i, x_i+1, x_i^2, x_i x_i+1, x_i+1^2 (x_i+1^4 is a term of the next
    # summand); the last clique has no x_{n-1}^4, so neither x_{n-1}^2 nor x_{n-2} x_{n-1}
    assert sorted(len(b) for b, _ in con.gram_blocks) == [4] + [6] * (n - 2)
    names = {c.name for c in sol.verify().checks}
    assert {psd.name for _, psd in con.gram_blocks} <= names            # every block is checked


def test_a_bad_clique_block_fails_the_independent_check():
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(rosenbrock(4) - g, sparsity="correlative")
    prog.maximize(g)
    sol = prog.solve(scale=False)
    assert sol.usable
    _, psd = con.gram_blocks[1]
    x = sol.x.copy()
    x[positions(sol.data.ids, psd.ids)] = matrix_to_svec(-np.eye(psd.size))
    forged = sd.Solution(prog, sol.data, "optimal", x, "forged", "direct", {})
    report = forged.verify()
    assert not report.passed
    failed = {c.name: c for c in report.failures}
    assert set(failed) == {con.name, psd.name}          # the identity and the block itself
    assert failed[psd.name].min_eig == pytest.approx(-1.0)
    assert failed[psd.name].kind == "clique"


@pytest.mark.parametrize("n", [6, 8, pytest.param(12, marks=pytest.mark.slow)])   # 12: a support Qhull cannot start on
def test_dense_chained_rosenbrock_bound_is_proven_and_below_the_minimum(n):
    # f(1, ..., 1) = 0 and f is a sum of squares: the minimum and the dense relaxation's optimum are
    # 0. Every dense Gram matrix of f - 0 is singular (along z(1), x_n + x_(n-1)^2 and the rows
    # x_(n-1) x_j, j < n - 1, which no certificate uses), so the bound needs a proof on that face
    f = rosenbrock(n)
    assert f([[1.0] * n])[0] == 0.0
    lb = minimize_on(f)
    assert lb.solution.verified
    assert -1e-6 <= lb.value <= 0.0


def test_dense_chained_rosenbrock_at_n20_is_refused_with_a_sparsity_hint():
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(rosenbrock(20) - g)
    prog.maximize(g)
    with pytest.raises(sd.ResourceLimitError, match="sparsity='correlative'"):
        prog.solve()


def test_term_sparsity_gives_the_dense_bound():
    # f = x^4 + x^2 + (y^2 - 1)^2: min 0 at (0, +-1). Newton basis 1, x, y, x^2, xy, y^2; the
    # term graph links b_i, b_j when b_i + b_j is a term or an even square: blocks
    # {1, x^2, y^2} (x^2 y^2 = 2 * xy), {x}, {y}, {xy}
    x, y = sd.variables("x y")
    f = x**4 + x**2 + (y**2 - 1) ** 2
    dense = minimize_on(f)
    term = minimize_on(f, sparsity="term")
    assert dense.value == pytest.approx(0.0, abs=1e-6)
    assert term.value == pytest.approx(dense.value, abs=1e-6)
    assert sorted(len(b) for b, _ in term.constraint.gram_blocks) == [1, 1, 1, 3]


def test_constrained_correlative_chain_on_the_box():
    # min sum x_i x_{i+1} on [-1, 1]^8 is -7 (alternating signs); each term: x_i x_i+1 + 1 =
    # (x_i + x_i+1)^2 / 2 + (1 - x_i^2) / 2 + (1 - x_i+1^2) / 2, so degree 2 is exact
    n = 8
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    f = sum(xs[i] * xs[i + 1] for i in range(n - 1))
    lb = minimize_on(f, BasicSet.box(xs, -1, 1), degree=2, sparsity="correlative")
    assert lb.value == pytest.approx(-(n - 1), abs=1e-6)
    assert sorted(len(b) for b, _ in lb.constraint.gram_blocks) == [3] * (n - 1)   # 1, x_i, x_i+1


def test_rigorous_bound_over_clique_blocks():
    # the chain on [-1, 1]^6: min -5, proven in exact arithmetic over the 5 clique blocks
    xs = sd.variables(" ".join(f"x{i}" for i in range(6)))
    f = sum(xs[i] * xs[i + 1] for i in range(5))
    lb = minimize_on(f, BasicSet.box(xs, -1, 1), degree=2, sparsity="correlative", rigorous=True)
    assert lb.solution.bound.proven and len(lb.constraint.gram_blocks) == 5
    assert -5.0 - 1e-6 <= lb.value <= -5.0


def test_chordal_extension_of_a_cycle():
    # the 5-cycle is not chordal: minimum-degree elimination adds 2 chords, giving 3 triangles
    adj = [{(i - 1) % 5, (i + 1) % 5} for i in range(5)]
    cliques = chordal_cliques(adj)
    assert sorted(len(c) for c in cliques) == [3, 3, 3]
    covered = {frozenset((int(a), int(b))) for c in cliques for a in c for b in c if a != b}
    assert all(frozenset((i, (i + 1) % 5)) in covered for i in range(5))
    # a term x0 x2 links 0 and 2; a group joins 1 and 3
    support = np.array([[1, 0, 1, 0], [0, 0, 0, 2]])
    assert interaction_graph(4, support, [[1, 3]]) == [{2}, {3}, {0}, {1}]


def test_term_blocks_merge_until_stable_and_bad_sparsity_is_refused():
    basis = np.array([[0], [1], [2]])                      # 1, x, x^2 for p = 1 + x^4
    assert [b.tolist() for b in term_blocks(np.array([[0], [4]]), basis)] == [[0, 2], [1]]
    assert len(term_blocks(np.array([[0], [4], [1]]), basis)) == 1    # x links 1 and x; then all
    with pytest.raises(sd.InputError, match="correlative"):
        sparse_bases(np.array([[0], [4]]), "chordal")
    x, y = sd.variables("x y")
    with pytest.raises(sd.InputError, match="sparsity='term' only"):
        sd.SOSProgram().add_sos(x**2 + y**2, basis=[x, y], sparsity="correlative")

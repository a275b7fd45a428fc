"""Constraint handles: re-solve with update, reading a given solution, multipliers, DSOS,
matrix_form, the Gram polynomial's size check (sosdyn.sos.constraints)."""
import tracemalloc

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos import examples, matrix_form

(X,) = sd.variables("x")
x, y = sd.variables("x y")


def test_resolve_with_update_keeps_basis_and_gives_new_answer():
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(x**4 - 3 * x**2 + 2 - g)
    prog.maximize(g)
    first = prog.solve().value(g)
    basis_before = con.basis.exps.copy()
    con.update(x**4 - 3 * x**2 + 5 - g)
    second = prog.solve().value(g)
    assert np.array_equal(con.basis.exps, basis_before)
    assert first == pytest.approx(2 - 9 / 4, abs=1e-6)
    assert second == pytest.approx(first + 3, abs=1e-6)


def test_a_constraint_handle_reads_the_solution_it_belongs_to():
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(X**4 - 3 * X**2 + 2 - g)
    prog.maximize(g)
    first = prog.solve()
    Q1 = first.gram_matrix(con)
    con.update(X**4 - 5 * X**2 + 7 - g)              # same basis, minimum 0.75 at x^2 = 5/2
    second = prog.solve()
    assert (first.value(g), second.value(g)) == (pytest.approx(-0.25, abs=1e-7), pytest.approx(0.75, abs=1e-7))
    np.testing.assert_array_equal(con.gram_matrix(first), Q1)          # the handle, given a solution
    np.testing.assert_array_equal(first.gram_matrix(con), Q1)          # the solution, given a handle
    np.testing.assert_array_equal(con.gram_matrix(second), second.gram_matrix(con))
    assert np.abs(con.gram_matrix(second) - Q1).max() > 0.5
    with pytest.raises(sd.InputError, match=r"Try: pass the solution: sol.gram_matrix\(con\)"):
        con.gram_matrix()                          # no default: the program keeps no solution
    (mult,) = sd.SOSProgram().add_nonneg_on(X**2, ineqs=[1 - X**2]).multipliers
    with pytest.raises(sd.InputError, match="pass the solution"):
        mult.value()
    with pytest.raises(sd.InputError, match="changed after this solve"):
        first.verify(eig_tol=1e-9)                 # cannot be re-checked against the new program


def test_multipliers_are_public_and_reproduce_the_certificate():
    prog, (a, b, c) = examples.probability_bound()
    sol = prog.solve()
    con = prog.sos_constraints[1]                  # q - 1 >= 0 on [4, 5]
    (mult,) = con.multipliers
    pts = np.linspace(-3, 8, 41)[:, None]
    np.testing.assert_allclose(mult.constraint(pts, ["x"]), (pts[:, 0] - 4) * (5 - pts[:, 0]))
    S = mult.gram_matrix(sol)
    assert S.shape == (len(mult.basis), len(mult.basis)) and np.linalg.eigvalsh(S).min() > -1e-9
    # independent of verify(): evaluate both sides of q - 1 - sigma g = z^T Q z at points
    zs = np.column_stack([m(pts, ["x"]) for m in mult.basis.monomials()])
    sigma = np.einsum("ni,ij,nj->n", zs, S, zs)
    value = mult.value(sol)                        # sigma has degree 0 here: a number
    np.testing.assert_allclose(value(pts, ["x"]) if isinstance(value, Polynomial) else value, sigma, atol=1e-9)
    z = np.column_stack([m(pts, ["x"]) for m in con.basis.monomials()])
    rhs = np.einsum("ni,ij,nj->n", z, sol.gram_matrix(con), z)
    q = sol.value(a) + sol.value(b) * pts[:, 0] + sol.value(c) * pts[:, 0] ** 2
    np.testing.assert_allclose(q - 1 - sigma * mult.constraint(pts, ["x"]), rhs, atol=1e-6)


def test_dsos_is_an_lp_inner_approximation():
    x, y = sd.variables("x y")
    # (x + y)^2 has the diagonally dominant Gram [[1, 1], [1, 1]]; (x + 2y)^2 has [[1, 2], [2, 4]],
    # its only Gram matrix on the basis {x, y}, which is PSD but not diagonally dominant.
    for p, dsos_ok in [((x + y) ** 2, True), ((x + 2 * y) ** 2, False)]:
        prog = sd.SOSProgram()
        prog.add_sos(p, cone="dsos")
        sol = prog.solve()
        assert sol.verified is dsos_ok                         # a certificate proven, or none
        assert not prog.compile().psd                          # no SDP block at all
    # as a lower bound it is weaker than SOS, never stronger
    p = x**4 + y**4 + x**2 * y**2 - 2 * x * y + 1
    bounds = {}
    for cone in ("psd", "dsos"):
        prog = sd.SOSProgram()
        g = prog.new_var()
        prog.add_sos(p - g, cone=cone)
        prog.maximize(g)
        bounds[cone] = prog.solve().value(g)
    assert bounds["dsos"] <= bounds["psd"] + 1e-7
    assert bounds["psd"] - bounds["dsos"] > 1e-3


def test_a_dense_new_sos_is_refused_before_its_coefficients_are_allocated():
    # its coefficient array alone would be 26796 x 26797 doubles (5.7 GB): the refusal comes first
    tracemalloc.start()
    try:
        with pytest.raises(sd.ResourceLimitError, match="Gram polynomial over 231 monomials"):
            sd.SOSProgram().new_sos([x, y], 40)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20


def test_matrix_form_is_the_scalar_form_and_the_multipartite_basis():
    P = PolyMatrix([[x**2 + 2, x**2], [x**2, x**2 + 2]])
    q, basis = matrix_form(P)
    y0, y1 = sd.variables("_y0 _y1")
    assert q.vars == ("x", "_y0", "_y1")
    assert q.allclose((x**2 + 2) * y0**2 + 2 * x**2 * y0 * y1 + (x**2 + 2) * y1**2, atol=0)
    # z_i from the Newton polytope of P_ii = x^2 + 2: {1, x}, times y_i
    assert {tuple(r) for r in basis} == {(0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1)}
    assert matrix_form(P, with_basis=False)[1].shape == (0, 3)
    with pytest.raises(sd.NotSymmetricError):
        matrix_form(PolyMatrix([[x, y], [1.0, x]]))

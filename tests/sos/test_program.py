"""SOS program API: back ends agree, re-solve without recompiling, cvxpy interop, errors."""
import cvxpy as cp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sosdyn as sd
from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos import newton_basis


def lower_bound(p, **solve_kw):
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(p - g)
    prog.maximize(g)
    return prog.solve(**solve_kw).value(g)


def test_direct_and_cvxpy_backends_agree():
    x, y = sd.variables("x y")
    p = x**4 + y**4 - 2 * x**2 * y + 3 * x * y + 1
    direct = lower_bound(p)
    via_cvxpy = lower_bound(p, backend="cvxpy")
    via_scs = lower_bound(p, solver="SCS", eps=1e-9)
    assert direct == pytest.approx(via_cvxpy, rel=1e-6)
    assert direct == pytest.approx(via_scs, rel=1e-3)
    # global minimum found by brute force is an upper bound, close to the SOS bound (n=2, deg 4: exact)
    g = np.linspace(-2, 2, 801)
    XX, YY = np.meshgrid(g, g)
    brute = p(np.column_stack([XX.ravel(), YY.ravel()]), ["x", "y"]).min()
    assert direct <= brute + 1e-9 and brute - direct < 1e-3


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


def test_cvxpy_constraints_and_objectives_interoperate():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    a = prog.new_var()
    b = prog.new_var()
    prog.add_sos(a * x**2 + b * y**2 - x * y)          # needs 4ab >= 1
    prog.add_constraint(prog.expr(a) <= 2)
    prog.minimize(cp.square(prog.expr(a) - 1) + cp.square(prog.expr(b) - 0.1))
    sol = prog.solve()
    assert sol.backend == "cvxpy" and sol.status == "optimal"
    av, bv = sol.value(a), sol.value(b)
    assert 4 * av * bv >= 1 - 1e-5
    assert av <= 2 + 1e-6


def test_least_squares_objective_and_linear_constraints():
    prog = sd.SOSProgram()
    u = prog.new_var(3)
    target = np.array([1.0, -2.0, 0.5])
    prog.minimize(sd.sum_squares([u[i, 0] - target[i] for i in range(3)]))
    prog.add_ge(u[1, 0], -1.0)
    prog.add_eq(u[2, 0], 0.0)
    sol = prog.solve()
    np.testing.assert_allclose(sol.value(u).ravel(), [1.0, -1.0, 0.0], atol=1e-6)
    assert sol.objective == pytest.approx(1.0 + 0.25, abs=1e-6)


def test_psd_matrix_variable_lmi_lyapunov():
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    prog = sd.SOSProgram()
    P = prog.new_psd(2)
    prog.add_eq(P[0, 0] + P[1, 1], 2.0)
    prog.add_sos_matrix(-(A.T @ P + P @ A) - 0.1 * PolyMatrix.identity(2))
    sol = prog.solve()
    Pv = sol.value(P)
    assert np.linalg.eigvalsh(Pv).min() > 0
    assert np.linalg.eigvalsh(A.T @ Pv + Pv @ A).max() <= -0.1 + 1e-6


def test_infeasible_is_reported_and_value_raises_typed_error():
    x, = sd.variables("x")
    prog = sd.SOSProgram()
    prog.add_sos(x**3)                         # odd degree: cannot be SOS
    sol = prog.solve()
    assert sol.status == "infeasible"
    with pytest.raises(sd.InfeasibleError, match="Try"):
        prog.solve(raise_on_failure=True)


def test_bad_program_inputs():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    with pytest.raises(sd.InputError, match="unknown solver"):
        prog.solve(solver="NOPE")
    with pytest.raises(sd.NotSymmetricError):
        prog.add_sos_matrix(PolyMatrix([[x, y], [1.0, x]]))
    with pytest.raises(sd.PolynomialError, match="must not depend on x"):
        prog.maximize(x)
    with pytest.raises(sd.PolynomialError, match="even degree"):
        prog.new_sos([x], 3)
    other = sd.SOSProgram().new_var()
    prog.add_sos(x**2 + other)
    with pytest.raises(sd.PolynomialError, match="another SOSProgram"):
        prog.solve()
    with pytest.raises(sd.InputError, match="cvxpy constraint"):
        sd.SOSProgram().add_constraint("x >= 0")
    with pytest.raises(sd.InputError, match="Clarabel setting"):
        p2 = sd.SOSProgram(); p2.add_sos(x**2); p2.solve(not_a_setting=1)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(st.integers(0, 10_000), st.sampled_from([1, 2]))
def test_random_gram_polynomials_are_found_sos_and_reconstructed(seed, half_degree):
    """z^T Q z with Q PSD random must be SOS; the recovered Gram reproduces the polynomial."""
    rng = np.random.default_rng(seed)
    from sosdyn.poly import monomials_up_to
    z = monomials_up_to(2, half_degree)
    L = rng.normal(size=(len(z), len(z)))
    Q = L @ L.T + 1e-3 * np.eye(len(z))
    p = Polynomial(("x", "y"), (z[:, None] + z[None]).reshape(-1, 2), Q.ravel())
    prog = sd.SOSProgram()
    con = prog.add_sos(p)
    sol = prog.solve()
    assert sol.usable
    Qr = con.gram_matrix()
    B = con.basis.exps
    back = Polynomial(("x", "y"), (B[:, None] + B[None]).reshape(-1, 2), Qr.ravel())
    assert back.allclose(p, atol=1e-6 * np.abs(Q).max())


@settings(max_examples=10, deadline=None, derandomize=True)
@given(st.floats(0.2, 5.0), st.floats(0.2, 5.0), st.booleans())
def test_motzkin_stays_not_sos_under_scaling_and_permutation(a, b, swap):
    x, y = sd.variables("x y")
    u, v = (b * y, a * x) if swap else (a * x, b * y)
    M = u**4 * v**2 + u**2 * v**4 + 1 - 3 * u**2 * v**2
    prog = sd.SOSProgram()
    prog.add_sos(M)
    assert prog.solve().status == "infeasible"


def test_newton_basis_of_a_homogeneous_form():
    x, y = sd.variables("x y")
    p = x**6 + y**6
    b = newton_basis(p.exps)
    assert {tuple(r) for r in b} == {(3, 0), (2, 1), (1, 2), (0, 3)}


def test_dsos_is_an_lp_inner_approximation():
    x, y = sd.variables("x y")
    # (x + y)^2 has the diagonally dominant Gram [[1, 1], [1, 1]]; (x + 2y)^2 has [[1, 2], [2, 4]],
    # its only Gram matrix on the basis {x, y}, which is PSD but not diagonally dominant.
    for p, dsos_ok in [((x + y) ** 2, True), ((x + 2 * y) ** 2, False)]:
        prog = sd.SOSProgram()
        prog.add_sos(p, cone="dsos")
        sol = prog.solve()
        assert (sol.status == "optimal") is dsos_ok
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

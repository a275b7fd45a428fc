"""Back ends agree; the memory estimate before every solve; solver answers out of bounds."""

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import backends
from sosdyn.sos.backends import solver_bytes


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


def test_degree_40_dense_sos_is_refused_before_the_solver(dense_program, no_solver):
    prog, _ = dense_program(40)
    with pytest.raises(sd.ResourceLimitError, match=r"231 x 231.*GiB.*dsos.*SCS.*set_limits"):
        prog.solve()                                   # no_solver: any solver call fails the test
    # Gram basis 231 (svec 26796), 861 equality rows: D = 27657, 56 D^2 bytes ~ 39.9 GiB
    est = solver_bytes(prog.compile(), "CLARABEL", "direct")
    assert 39 * 2**30 < est < 41 * 2**30


def test_the_estimate_grows_like_the_square_of_the_svec_size(dense_program):
    est = [solver_bytes(dense_program(d)[0].compile(), "CLARABEL", "direct") for d in (8, 16, 24, 32, 40)]
    assert all(a < b for a, b in zip(est, est[1:]))
    # Clarabel 0.11's measured peak RSS: 58 MiB at degree 16, 882 MiB at 24 -- bounded within 2x
    assert 58 * 2**20 < est[1] < 2 * 58 * 2**20 and 882 * 2**20 < est[2] < 2 * 882 * 2**20
    # svec 26796 vs 4186: the dense term grows by (27657 / 4511)^2 = 37.6
    assert 30 < est[4] / est[2] < 40


def test_the_limit_decides_and_raising_it_lets_the_solve_through(dense_program):
    prog, g = dense_program(8)
    est = solver_bytes(prog.compile(), "CLARABEL", "direct")
    with sd.limits(max_bytes=int(est) - 1):
        with pytest.raises(sd.ResourceLimitError):
            prog.solve()
    with sd.limits(max_bytes=int(est) + 1):
        sol = prog.solve()
    assert sol.verified and sol.value(g) == pytest.approx(1.0, abs=1e-6)


def test_first_order_and_lp_alternatives_are_estimated_far_smaller(dense_program):
    prog, _ = dense_program(40)
    data = prog.compile()
    assert solver_bytes(data, "SCS", "cvxpy") < 0.5 * 2**30          # measured 164 MiB peak
    assert solver_bytes(data, "CLARABEL", "cvxpy") > solver_bytes(data, "CLARABEL", "direct")
    small, _ = dense_program(16, cone="dsos")
    dsos = small.compile()
    assert not dsos.psd and solver_bytes(dsos, "CLARABEL", "direct") < 64 * 2**20


def test_a_solver_answer_beyond_the_polynomial_bounds_is_a_solver_error(dense_program, monkeypatch):
    real = backends._clarabel

    def huge(data, verbose, settings):
        status, x, raw, seconds, info = real(data, verbose, settings)
        return status, np.full(x.size, 1e200), raw, seconds, info

    monkeypatch.setattr(backends, "_clarabel", huge)
    prog, g = dense_program(4)
    sol = prog.solve()
    assert sol.status == "solver_error" and "above 1e+150" in sol.raw_status


@pytest.mark.parametrize("backend,solver", [("direct", "CLARABEL"), ("cvxpy", "CLARABEL"), ("cvxpy", "CVXOPT")])
def test_psd_duals_are_complementary_to_the_gram_matrices(backend, solver):
    # max g with x^4 - 3x^2 + 2 - g SOS: at the optimum <Q, S> = 0 (complementary slackness) and
    # S is the moment matrix of the two minimisers +-sqrt(3/2), weights 1/2: S/S_00 = [[1,0,1.5],[0,1.5,0],[1.5,0,2.25]]
    if solver == "CVXOPT":
        pytest.importorskip("cvxopt")
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(x**4 - 3 * x**2 + 2 - g)
    prog.maximize(g)
    sol = prog.solve(backend=backend, solver=solver)
    (S,) = sol.info["psd_duals"]
    Q = sol.gram_matrix(con)
    assert abs(np.sum(Q * S)) <= 1e-6 * np.abs(Q).max() * np.abs(S).max()
    assert S / S[0, 0] == pytest.approx(np.array([[1, 0, 1.5], [0, 1.5, 0], [1.5, 0, 2.25]]), abs=1e-3)

"""Resource estimates before every solve and the conditioning rule of the conic data."""
import time

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import backends
from sosdyn.sos.backends import solver_bytes
from sosdyn.sos.conic import coupled_psd_sizes
from sosdyn.sos.newton import gram_matching_bytes

x, y = sd.variables("x y")


def dense_program(degree, **kw):
    """max g s.t. (1 + x^2 + y^2)^(degree/2) - g SOS: a dense Gram basis, answer g = 1."""
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos((1 + x**2 + y**2) ** (degree // 2) - g, **kw)
    prog.maximize(g)
    return prog, g


@pytest.fixture
def no_solver(monkeypatch):
    def refuse(*args):
        raise AssertionError("the solver was called")
    monkeypatch.setattr(backends, "_clarabel", refuse)
    monkeypatch.setattr(backends, "_cvxpy", refuse)


def test_degree_40_dense_sos_is_refused_promptly_before_the_solver(no_solver):
    t0 = time.perf_counter()
    prog, _ = dense_program(40)
    with pytest.raises(sd.ResourceLimitError, match=r"231 x 231.*GiB.*dsos.*SCS.*set_limits"):
        prog.solve()
    assert time.perf_counter() - t0 < 2.0
    # Gram basis 231 (svec 26796), 861 equality rows: D = 27657, 56 D^2 bytes ~ 39.9 GiB
    est = solver_bytes(prog.compile(), "CLARABEL", "direct")
    assert 39 * 2**30 < est < 41 * 2**30


def test_the_estimate_grows_like_the_square_of_the_svec_size():
    est = [solver_bytes(dense_program(d)[0].compile(), "CLARABEL", "direct") for d in (8, 16, 24, 32, 40)]
    assert all(a < b for a, b in zip(est, est[1:]))
    # Clarabel 0.11's measured peak RSS: 58 MiB at degree 16, 882 MiB at 24 -- bounded within 2x
    assert 58 * 2**20 < est[1] < 2 * 58 * 2**20 and 882 * 2**20 < est[2] < 2 * 882 * 2**20
    # svec 26796 vs 4186: the dense term grows by (27657 / 4511)^2 = 37.6
    assert 30 < est[4] / est[2] < 40


def test_the_limit_decides_and_raising_it_lets_the_solve_through():
    prog, g = dense_program(8)
    est = solver_bytes(prog.compile(), "CLARABEL", "direct")
    with sd.limits(max_bytes=int(est) - 1):
        with pytest.raises(sd.ResourceLimitError):
            prog.solve()
    with sd.limits(max_bytes=int(est) + 1):
        sol = prog.solve()
    assert sol.status == "optimal" and sol.value(g) == pytest.approx(1.0, abs=1e-6)


def test_first_order_and_lp_alternatives_are_estimated_far_smaller():
    prog, _ = dense_program(40)
    data = prog.compile()
    assert solver_bytes(data, "SCS", "cvxpy") < 0.5 * 2**30          # measured 164 MiB peak
    assert solver_bytes(data, "CLARABEL", "cvxpy") > solver_bytes(data, "CLARABEL", "direct")
    small, _ = dense_program(16, cone="dsos")
    dsos = small.compile()
    assert not dsos.psd and solver_bytes(dsos, "CLARABEL", "direct") < 64 * 2**20


def test_blocks_sharing_equality_rows_are_estimated_as_one_dense_group():
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_nonneg_on(x**4 + y**4 - g, ineqs=[1 - x**2 - y**2], degree=4)   # Gram 6 + multiplier 3
    prog.add_sos(x**2 + y**2 + 1 - g)                                        # Gram 3, own rows
    prog.new_psd(2)                                                           # no rows at all
    prog.maximize(g)
    D = sorted(coupled_psd_sizes(prog.compile()))
    # 21 + 6 svec entries and the 15 monomials of degree <= 4; 6 + the 6 of degree <= 2; 3
    assert D == [3, 12, 42]


def test_gram_matching_is_checked_before_it_allocates():
    assert gram_matching_bytes(66, 2) == 8.0 * 2211 * 16
    with sd.limits(max_bytes=int(gram_matching_bytes(66, 2)) - 1):
        with pytest.raises(sd.ResourceLimitError, match="Gram basis of 66 monomials"):
            sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10)
    assert len(sd.SOSProgram().add_sos((1 + x**2 + y**2) ** 10).basis) == 66


def test_a_dense_new_sos_is_refused_before_its_coefficients_are_allocated():
    t0 = time.perf_counter()
    with pytest.raises(sd.ResourceLimitError, match="Gram polynomial over 231 monomials"):
        sd.SOSProgram().new_sos([x, y], 40)
    assert time.perf_counter() - t0 < 1.0


# ---------------------------------------------------------------- conditioning of the data
@pytest.mark.parametrize("make", [
    lambda g: 1e100 * x**4 + 1 - g,          # was reported infeasible
    lambda g: x**4 + 3e9 * x**2 + 1 - g,     # was reported infeasible (answer: g = 1)
    lambda g: 1e12 * x**4 + 1 - g,           # was reported optimal with g = -15.7
])
def test_badly_scaled_programs_raise_instead_of_a_wrong_status(no_solver, make):
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(make(g), name="scaled")
    prog.maximize(g)
    with pytest.raises(sd.InputError, match=r"'scaled'.*above 1e\+08.*Try: rescale the variables"):
        prog.solve()


def test_moderately_scaled_programs_still_solve():
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(1e6 * (x**4 + 1) - g)
    prog.maximize(g)
    sol = prog.solve()
    assert sol.status == "optimal" and sol.value(g) == pytest.approx(1e6, rel=1e-6)
    assert prog.compile().rhs_ratio == pytest.approx(1e6)


def test_a_solver_answer_beyond_the_polynomial_bounds_is_a_solver_error(monkeypatch):
    real = backends._clarabel

    def huge(data, verbose, settings):
        status, x, raw, seconds, info = real(data, verbose, settings)
        return status, np.full(x.size, 1e200), raw, seconds, info

    monkeypatch.setattr(backends, "_clarabel", huge)
    prog, g = dense_program(4)
    sol = prog.solve()
    assert sol.status == "solver_error" and "above 1e+150" in sol.raw_status

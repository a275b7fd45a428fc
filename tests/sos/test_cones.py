"""The cone of a Gram block, cone="psd" | "sdsos" | "dsos" (sosdyn.sos.constraints, program).

Known answers: bounds tighten DSOS <= SDSOS <= SOS (for a maximised lower bound) on
textbook problems, two of them with every optimum derived by hand; the independent check of
SDSOS blocks (Q PSD, as numbers); the structure each cone lowers to; typed errors.
"""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix
from sosdyn.sos.cones import CONES
from sosdyn.sos.gram import matrix_to_svec

(X,) = sd.variables("x")
x, y = sd.variables("x y")
ORDER = ("dsos", "sdsos", "psd")       # smallest feasible set first


def lower_bound(p, cone, **solve):
    """max g such that p - g has a Gram matrix in ``cone``."""
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(p - g, cone=cone)
    prog.maximize(g)
    return prog.solve(raise_on_failure=True, **solve).objective


# ---------------------------------------------------------------------- derived by hand
def test_three_by_three_gram_closed_forms_strictly_ordered():
    # p = 1 + x/2 + y/2 + x^2 + y^2 + xy. In the basis z = (1, x, y) every product z_i z_j is a
    # different monomial, so the Gram matrix of p - g is unique:
    #     Q(g) = [[1 - g, u, u], [u, 1, w], [u, w, 1]],   u = 1/4, w = 1/2.
    # SOS:   Q >= 0 <=> 1 - g >= [u u] [[1, w], [w, 1]]^-1 [u u]^T = 2u^2/(1 + w) = 1/12,
    #        g = 11/12 (= min p, at x = y = -1/6).
    # DSOS:  rows 2, 3 hold (1 >= u + w); row 1: 1 - g >= 2u, g = 1/2.
    # SDSOS: Q = M12 + M13 + M23 + D with 2x2 PSD blocks. Q is symmetric under swapping
    #        indices 2, 3 and the cone is convex, so a symmetric decomposition is optimal:
    #        M23 = [[a, w], [w, a]] (a >= w), M12, M13 = [[b, u], [u, c]] (b c >= u^2),
    #        a + c <= 1. Best: a = w, c = 1 - w, b = u^2/(1 - w); 1 - g = 2b, g = 1 - 2u^2/(1 - w) = 3/4.
    p = 1 + x / 2 + y / 2 + x**2 + y**2 + x * y
    bounds = {cone: lower_bound(p, cone) for cone in ORDER}
    assert bounds["dsos"] == pytest.approx(1 / 2, abs=1e-6)
    assert bounds["sdsos"] == pytest.approx(3 / 4, abs=1e-6)
    assert bounds["psd"] == pytest.approx(11 / 12, abs=1e-6)


def test_two_by_two_sdsos_is_sos_and_dsos_is_weaker():
    # x^2 + x + 1 - g, basis (1, x): Q = [[1 - g, 1/2], [1/2, 1]]. Every 2x2 PSD matrix is
    # scaled diagonally dominant, so SDSOS = SOS: 1 - g >= 1/4, g = 3/4; DSOS: 1 - g >= 1/2.
    p = X**2 + X + 1
    assert lower_bound(p, "dsos") == pytest.approx(1 / 2, abs=1e-6)
    assert lower_bound(p, "sdsos") == pytest.approx(3 / 4, abs=1e-6)
    assert lower_bound(p, "psd") == pytest.approx(3 / 4, abs=1e-6)


def test_sos_matrix_cones_derived_by_hand():
    # [[x^2 + 2, x], [x, x^2 + 2]] - t I, basis (y0, x y0, y1, x y1): coefficient matching
    # leaves one free a (the split of the x y0 y1 coefficient) and, after permuting, two
    # 2x2 blocks [[2 - t, a], [a, 1]], [[1, 1 - a], [1 - a, 2 - t]].
    # SOS = SDSOS (2x2 blocks): 2 - t >= max(a^2, (1 - a)^2), a = 1/2, t = 7/4 (= min over x
    # of lambda_min = x^2 + 2 - |x|, at |x| = 1/2). DSOS: 2 - t >= max(|a|, |1 - a|), t = 3/2.
    out = {}
    for cone in ORDER:
        prog = sd.SOSProgram()
        t = prog.new_var()
        con = prog.add_sos_matrix(PolyMatrix([[X**2 + 2, X], [X, X**2 + 2]]) - t * PolyMatrix.identity(2),
                                  cone=cone)
        prog.maximize(t)
        out[cone] = prog.solve(raise_on_failure=True).objective
        assert con.psd.cone == cone and con.psd.size == 4
    assert out["dsos"] == pytest.approx(3 / 2, abs=1e-6)
    assert out["sdsos"] == pytest.approx(7 / 4, abs=1e-6)
    assert out["psd"] == pytest.approx(7 / 4, abs=1e-6)


# ---------------------------------------------------------------------- textbook problems
def chebyshev(cone, degree=8):
    """examples.chebyshev with every Gram block (main and multipliers) in ``cone``."""
    prog = sd.SOSProgram()
    p = prog.new_poly([X], degree)
    for q in (1 - p, 1 + p):
        prog.add_nonneg_on(q, ineqs=[1 - X**2], degree=degree, cone=cone)
    prog.maximize(p.coeff(X**degree))
    return prog


def test_chebyshev_bounds_tighten_dsos_sdsos_sos():
    # SOS gives the known 128 (T_8); the inner approximations strictly less (measured:
    # DSOS 14, SDSOS 67.9411 -- the optima of an LP and an SOCP, so unique values).
    out = {}
    for cone in ORDER:
        sol = chebyshev(cone).solve(raise_on_failure=True)
        out[cone] = sol.objective
    assert 128 * (1 - 1e-6) <= out["psd"] <= 128          # proven: on the safe side, within 1e-6
    assert out["dsos"] == pytest.approx(14, abs=1e-5)
    assert out["sdsos"] == pytest.approx(67.94112, abs=1e-3)
    assert out["dsos"] < out["sdsos"] - 1 and out["sdsos"] < out["psd"] - 1


def test_putinar_sdsos_with_2x2_blocks_gives_the_sos_answer():
    # examples.probability_bound (minimise; SOS optimum 1/37): the main Gram blocks are 2x2
    # (basis (1, x)), where SDSOS = PSD, the multipliers constants (1x1: SDSOS = PSD = ">= 0"),
    # so the SDSOS optimum is also 1/37.
    # DSOS is a smaller feasible set: a larger minimum (measured 35/124).
    def run(cone, multiplier_cone=None):
        prog = sd.SOSProgram()
        a, b, c = (prog.new_var() for _ in range(3))
        q = a + b * X + c * X**2
        cons = [prog.add_nonneg_on(q, ineqs=[X * (5 - X)], degree=2, cone=cone, multiplier_cone=multiplier_cone),
                prog.add_nonneg_on(q - 1, ineqs=[(X - 4) * (5 - X)], degree=2, cone=cone,
                                   multiplier_cone=multiplier_cone)]
        prog.minimize(a + b + 1.25 * c)
        return prog, cons, prog.solve(raise_on_failure=True)

    prog, cons, sol = run("sdsos")
    assert sol.objective == pytest.approx(1 / 37, abs=1e-6)
    assert all(b.psd.cone == "sdsos" for b in prog.blocks if b.psd is not None)
    assert [m.psd.cone for con in cons for m in con.multipliers] == ["sdsos", "sdsos"]
    data = prog.compile()
    assert not data.psd and data.n_soc == 2          # two 2x2 blocks, one cone each
    assert sol.verify().passed and {c.cone for c in sol.verify().checks if c.kind != "ge"} == {"sdsos"}
    dsos = run("dsos")[2].objective
    assert dsos == pytest.approx(35 / 124, abs=1e-6) and dsos > sol.objective + 0.1
    mixed, cons, sol = run("dsos", multiplier_cone="psd")
    assert [m.psd.cone for con in cons for m in con.multipliers] == ["psd", "psd"]
    assert len(mixed.compile().psd) == 2 and 1 / 37 - 1e-6 <= sol.objective <= dsos + 1e-6


# ---------------------------------------------------------------------- structure of each cone
def test_each_cone_lowers_to_its_own_structure():
    # Gram sizes 6 (add_sos), 3 (new_sos), 2 (family): 3 PSD blocks for "psd"; for "sdsos"
    # one 3-dim second-order cone per off-diagonal pair, 15 + 3 + 1, and one row per diagonal
    # entry, 6 + 3 + 2; for "dsos" rows only, two per pair and one per diagonal entry.
    for cone, n_psd, n_soc in [("psd", 3, 0), ("sdsos", 0, 19), ("dsos", 0, 0)]:
        prog = sd.SOSProgram()
        con = prog.add_sos(x**4 + y**4 + x**2 * y**2 + 1, cone=cone)          # Newton: 1, x, y, x^2, xy, y^2
        prog.new_sos([x, y], 2, cone=cone)                                       # basis 1, x, y
        fam = prog.add_sos_matrix_family([PolyMatrix([[X**2 + 1]])], [1.0], cone=cone)  # y0, x y0
        data = prog.compile()
        assert {b.psd.cone for b in prog.blocks if b.psd is not None} == {cone}
        assert (len(con.basis), len(fam.basis)) == (6, 2)
        assert (len(data.psd), data.n_soc, data.sizes()["second_order_cones"]) == (n_psd, n_soc, n_soc)
        assert data.A_ge.shape[0] == {"psd": 0, "sdsos": 6 + 3 + 2, "dsos": 2 * 19 + 6 + 3 + 2}[cone]


@pytest.mark.parametrize("cone, before, after, per_pair", [("sdsos", 3 / 4, -4 / 3, 1), ("dsos", 1 / 2, -2.0, 0)])
def test_update_keeps_the_cone_and_drops_the_old_auxiliary_rows(cone, before, after, per_pair):
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_sos(1 + x / 2 + y / 2 + x**2 + y**2 + x * y - g, cone=cone)
    prog.maximize(g)
    assert prog.solve().objective == pytest.approx(before, abs=1e-6)
    con.update(x**4 + y**4 + x**2 * y**2 - 4 * x * y - g)    # support outgrows the basis
    n = len(con.basis)
    assert con.psd.cone == cone and prog.compile().n_soc == per_pair * n * (n - 1) // 2
    assert len(prog.linear) == {"sdsos": 2, "dsos": 1}[cone]     # only the new block's rows
    # SDSOS = SOS here (both -4/3 = min p, at x = y = +-(2/3)^(1/2)); DSOS -2 (measured)
    assert prog.solve(raise_on_failure=True).objective == pytest.approx(after, abs=1e-6)


def test_sdsos_rigorous_bound_and_cvxpy_backend_agree_with_the_closed_form():
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(1 + x / 2 + y / 2 + x**2 + y**2 + x * y - g, cone="sdsos")
    prog.maximize(g)
    rig = prog.solve(rigorous=True)
    # the proof is of the certificate (Q PSD, exactly), so the proven g may sit a hair above
    # the SDSOS optimum 3/4; it is a true lower bound on p (min 11/12) either way
    assert rig.bound.proven == pytest.approx(3 / 4, abs=1e-6) and rig.bound.proven <= 11 / 12
    assert prog.solve(backend="cvxpy", raise_on_failure=True).objective == pytest.approx(3 / 4, abs=1e-6)


# ---------------------------------------------------------------------- independent check
def test_sdsos_block_is_checked_as_psd_numbers(forged):
    prog = sd.SOSProgram()
    s = prog.new_sos([x, y], 2, cone="sdsos")
    (block,) = [b.psd for b in prog.blocks if b.psd is not None]
    # Q = [[1, 1, 1], [1, 1, 1], [1, 1, 1]] is PSD but not scaled diagonally dominant in the
    # solver's sense (no auxiliary rows were solved): the certificate needs PSD only -> passes.
    sol = forged(prog, [(block, matrix_to_svec(np.ones((3, 3))))])
    assert sol.verify().passed and sol.value(s).nterms == 6
    # [[1, 2, 0], [2, 1, 0], [0, 0, 1]] has eigenvalue -1: fails, as numbers
    bad_Q = np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    (bad,) = forged(prog, [(block, matrix_to_svec(bad_Q))]).verify().failures
    assert (bad.cone, bad.kind) == ("sdsos", "sos_var") and bad.min_eig == pytest.approx(-1.0)
    assert "min eigenvalue" in bad.reason


# ---------------------------------------------------------------------- typed errors
@pytest.mark.parametrize("declare", [
    lambda prog: prog.add_sos(x**2 + 1, cone="sos"),
    lambda prog: prog.add_sos_matrix(PolyMatrix([[x**2 + 1]]), cone="SDSOS"),
    lambda prog: prog.add_nonneg_on(x, ineqs=[x], degree=2, multiplier_cone="lp"),
    lambda prog: prog.new_sos([x], 2, cone=None),
    lambda prog: prog.add_sos_matrix_family([PolyMatrix([[x**2 + 1]])], [1.0], cone="dd"),
])
def test_unknown_cone_is_refused_before_anything_is_declared(declare):
    prog = sd.SOSProgram()
    with pytest.raises(sd.InputError, match=r"unknown .*cone.*Try: 'psd'.*'sdsos'.*'dsos'"):
        declare(prog)
    assert not prog.blocks and not prog.linear and not prog.sos_constraints
    assert CONES == ("psd", "sdsos", "dsos")

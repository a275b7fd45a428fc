"""No unverified answer: every number a Solution hands out passes the independent check.

Each class of defect from issue 10: SCS answers marked optimal that are wrong, forged
certificates with a negative multiplier / new_sos / new_psd / non-dominant DSOS block, linear
rows; and a property test against a pointwise check (sosdyn.sos.verification).
"""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sosdyn as sd
from sosdyn.poly import PolyMatrix
from sosdyn.sos import examples
from sosdyn.sos.gram import matrix_to_svec

(X,) = sd.variables("x")


# ---------------------------------------------------------------------- SCS answers
def test_scs_optimal_but_wrong_chebyshev_is_refused():
    prog, p = examples.chebyshev()
    sol = prog.solve(solver="SCS")                            # SCS claims an optimum
    report = sol.verify()
    assert not report.passed and sol.outcome == "unverified" and not sol.verified
    with pytest.raises(sd.UnverifiedSolutionError, match="multiplier|nonneg") as exc:
        sol.value(p)
    assert exc.value.report is report and exc.value.status == "unverified"
    for access in (lambda: sol.objective, lambda: sol.gram_matrix(prog.sos_constraints[0]),
                   lambda: prog.sos_constraints[0].gram_matrix(sol),
                   lambda: prog.sos_constraints[0].multipliers[0].value(sol)):
        with pytest.raises(sd.UnverifiedSolutionError):
            access()


def test_scs_provably_false_lower_bound_is_never_returned():
    prog, g = examples.floudas(6)
    sol = prog.solve(solver="SCS", max_iters=2000)
    claimed = float(sol.values_of(g.ids)[0])
    true_min = examples.floudas_minimum()
    assert claimed > true_min + 0.1          # SCS's "lower bound" -5.27 is above the minimum -5.508
    try:                                     # what is returned is proven, so below the minimum
        assert sol.value(g) <= true_min
    except sd.UnverifiedSolutionError as exc:
        failing = {c.name for c in exc.report.failures}
        assert any(".sigma" in name for name in failing)     # multiplier Gram blocks are checked


@pytest.mark.parametrize("make, optimum", [(lambda: examples.probability_bound()[0], 1 / 37),
                                           (lambda: examples.matrix_program()[0], 2.0),
                                           (lambda: examples.floudas(6)[0], -20 / 3)])
def test_scs_answers_are_proven_on_the_safe_side_or_raise(make, optimum):
    # known optima of the programs themselves (the degree-6 Floudas relaxation: -20/3)
    prog = make()
    sol = prog.solve(solver="SCS", max_iters=5000)
    try:
        value = sol.objective
    except sd.UnverifiedSolutionError as exc:
        assert not sol.verified and "Tried" in str(exc)
        return
    assert sol.verified
    assert (value <= optimum) if prog.objective[0] == "max" else (value >= optimum)
    assert value == pytest.approx(optimum, rel=1e-3, abs=1e-6)


def test_a_certificate_of_t_above_the_supremum_is_refused(forged):
    prog, t, con = examples.matrix_program()
    good = prog.solve()
    assert good.value(t) == pytest.approx(2.0, abs=1e-8)
    Q = good.gram_matrix(con)
    sol = forged(prog, [(t, [2.000014]), (con.psd, matrix_to_svec(Q))], solver="SCS")
    report = sol.verify()
    assert not report.passed and report.failures[0].name == con.name
    assert report.failures[0].residual == pytest.approx(1.4e-5, rel=1e-3)
    with pytest.raises(sd.UnverifiedSolutionError, match="coefficient residual 1.40e-05"):
        sol.value(t)


# ---------------------------------------------------------------------- forged blocks
def test_negative_multiplier_cannot_prove_x2_at_least_a_quarter_on_the_interval(forged):
    # x^2 - 1/4 - sigma (1 - x^2) = 3/4 x^2 with sigma = -1/4: the main Gram diag(0, 3/4) is
    # PSD and matches exactly; only the multiplier's Gram [-1/4] is wrong (x = 0 violates it).
    prog = sd.SOSProgram("forged")
    con = prog.add_nonneg_on(X**2 - 0.25, ineqs=[1 - X**2], degree=2)
    (mult,) = con.multipliers
    assert [str(m) for m in con.basis.to_sympy()] == ["1", "x"]
    sol = forged(prog, [(mult.psd, [-0.25]), (con.psd, matrix_to_svec(np.diag([0.0, 0.75])))])
    report = sol.verify()
    assert not report.passed
    (bad,) = report.failures
    assert (bad.name, bad.kind, bad.min_eig) == (mult.psd.name, "multiplier", -0.25)
    assert report.checks[0].passed                         # the main identity itself holds
    assert sol.outcome == "unverified"
    with pytest.raises(sd.UnverifiedSolutionError, match="nonneg1.sigma0.*-2.500e-01"):
        sol.value(mult.poly)
    for access in (lambda: con.gram_matrix(sol), lambda: mult.gram_matrix(sol), lambda: mult.value(sol)):
        with pytest.raises(sd.UnverifiedSolutionError):
            access()
    np.testing.assert_allclose(sol.gram_matrix(mult, checked=False), [[-0.25]])


def test_new_sos_block_is_checked(forged):
    prog = sd.SOSProgram()
    s = prog.new_sos([X], 2)                                  # z = (1, x)
    con = prog.add_sos(X**2 + 1 - s)
    block = prog.blocks[0].psd
    assert block.role == "sos_var"
    # s = -1 (Gram diag(-1, 0)) makes x^2 + 1 - s = x^2 + 2 SOS with Gram diag(2, 1)
    sol = forged(prog, [(block, matrix_to_svec(np.diag([-1.0, 0.0]))),
                        (con.psd, matrix_to_svec(np.diag([2.0, 1.0])))])
    (bad,) = sol.verify().failures
    assert (bad.name, bad.kind, bad.min_eig) == (block.name, "sos_var", -1.0)
    with pytest.raises(sd.UnverifiedSolutionError):
        sol.value(s)


def test_new_psd_block_is_checked(forged):
    prog = sd.SOSProgram()
    P = prog.new_psd(2)
    con = prog.add_sos_matrix(P + PolyMatrix.identity(2))
    block = prog.blocks[0].psd
    # P = diag(-0.5, 1): P + I = diag(0.5, 2) is PSD, P is not
    sol = forged(prog, [(block, matrix_to_svec(np.diag([-0.5, 1.0]))),
                        (con.psd, matrix_to_svec(np.diag([0.5, 2.0])))])
    (bad,) = sol.verify().failures
    assert (bad.kind, bad.min_eig) == ("psd_var", -0.5)
    with pytest.raises(sd.UnverifiedSolutionError):
        sol.value(P)


def test_dsos_block_diagonal_dominance_is_checked_as_numbers(forged):
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    con = prog.add_sos((x + 2 * y) ** 2, cone="dsos")
    # its only Gram matrix [[1, 2], [2, 4]] is PSD but not diagonally dominant (1 < 2)
    order = [tuple(e) for e in con.basis.exps]
    Q = np.array([[1.0, 2.0], [2.0, 4.0]]) if order == [(1, 0), (0, 1)] else np.array([[4.0, 2.0], [2.0, 1.0]])
    sol = forged(prog, [(con.psd, matrix_to_svec(Q))])
    (bad,) = sol.verify().failures
    assert bad.cone == "dsos" and bad.residual < 1e-12 and bad.min_eig > -1e-12
    assert bad.dd_margin == pytest.approx(-1.0) and "diagonal dominance" in bad.reason
    with pytest.raises(sd.UnverifiedSolutionError, match="diagonal dominance violated by 1.00e"):
        sol.objective


def test_linear_rows_are_checked(forged):
    prog = sd.SOSProgram()
    a = prog.new_var()
    con = prog.add_sos(X**2 + a)
    prog.add_eq(a, 1.0)
    sol = forged(prog, [(a, [0.5]), (con.psd, matrix_to_svec(np.diag([0.5, 1.0])))])
    (bad,) = sol.verify().failures
    assert bad.kind == "eq" and bad.residual == pytest.approx(0.5)


# ---------------------------------------------------------------------- property
def independent_check(sol, prog, p, g, disk):
    """Pointwise: Gram blocks PSD and p - g - sum sigma_i g_i = z^T Q z at random points."""
    pts = np.random.default_rng(1).uniform(-2, 2, size=(60, 2))
    gv = sol.value(g)
    (con,) = prog.sos_constraints
    Q = sol.gram_matrix(con)
    assert np.linalg.eigvalsh(Q).min() >= -1e-6 * max(1.0, np.abs(Q).max())
    lhs = p(pts, ["x", "y"]) - gv
    for m in con.multipliers:
        S = m.gram_matrix(sol)
        assert np.linalg.eigvalsh(S).min() >= -1e-6 * max(1.0, np.abs(S).max())
        zs = np.column_stack([b(pts, ["x", "y"]) for b in m.basis.monomials()])
        lhs = lhs - np.einsum("ni,ij,nj->n", zs, S, zs) * disk(pts, ["x", "y"])
    z = np.column_stack([b.with_vars(("x", "y"))(pts, ["x", "y"]) for b in con.basis.monomials()])
    rhs = np.einsum("ni,ij,nj->n", z, Q, z)
    assert np.abs(lhs - rhs).max() <= 1e-4 * max(1.0, np.abs(lhs).max())
    return gv


@settings(max_examples=5, deadline=None, derandomize=True)
@given(st.integers(0, 10**6), st.sampled_from(["global", "disk"]))
def test_whatever_value_returns_passes_an_independent_check(random_program, seed, kind):
    outcomes = {}
    for solver, opts in (("CLARABEL", {}), ("SCS", {"max_iters": 3000})):
        prog, g, p, disk = random_program(seed, kind)
        sol = prog.solve(solver=solver, **opts)
        try:
            outcomes[solver] = independent_check(sol, prog, p, g, disk)
        except sd.UnverifiedSolutionError as exc:
            assert not exc.report.passed and not sol.verified
            outcomes[solver] = None
    assert outcomes["CLARABEL"] is not None                   # the accurate solver's answer counts
    if outcomes["SCS"] is not None:
        assert outcomes["SCS"] == pytest.approx(outcomes["CLARABEL"], abs=1e-3 * max(1, abs(outcomes["CLARABEL"])))

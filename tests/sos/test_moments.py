"""Moments (issue 15, item 1): moment matrices from the duals, atoms by flat extension,
pseudo-expectations, and the refusals (not flat, not PSD, not a moment matrix).

Known answers (by hand or from the literature):
* x^4 - 3x^2 + 2: derivative 4x^3 - 6x = 0 -> x = +-sqrt(3/2), value 9/4 - 9/2 + 2 = -1/4;
  by the symmetry x -> -x the central-path dual puts weight 1/2 on each minimiser.
* six-hump camel 4x^2 - 2.1x^4 + x^6/3 + xy - 4y^2 + 4y^4: global minimum -1.0316284535 at
  +-(0.0898420137, -0.7126564033) (Dixon & Szego test set).
* min x on the unit disc: -1 at (-1, 0).
* (x^2 + y^2 - 1)^2: minimum 0 on a whole circle: no finite atoms, the moments are not flat.
"""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos.examples import disc_minimum
from sosdyn.sos.moments import check_atoms, extract_atoms, moments_from_dual

CAMEL_MIN = -1.0316284535
CAMEL_POINT = np.array([0.0898420137, -0.7126564033])


def lower_bound(p, **solve):
    prog = sd.SOSProgram()
    g = prog.new_var(name="g")
    con = prog.add_sos(p - g)
    prog.maximize(g)
    return prog.solve(**solve), g, con


@pytest.fixture(scope="module")
def xy():
    return sd.variables("x y")


def test_double_well_minimisers_weights_and_expectations(xy):
    x, _ = xy
    p = x**4 - 3 * x**2 + 2
    sol, g, con = lower_bound(p)
    assert sol.value(g) == pytest.approx(-0.25, abs=1e-7)
    atoms = sol.minimizers(con)
    order = np.argsort(atoms.points[:, 0])
    assert atoms.points[order, 0] == pytest.approx([-np.sqrt(1.5), np.sqrt(1.5)], abs=1e-4)   # 3e-5
    assert atoms.weights[order] == pytest.approx([0.5, 0.5], abs=1e-6)
    m = sol.moments(con)
    assert m.matrix.shape == (3, 3) and m.rank() == 2
    assert m.expectation(p) == pytest.approx(-0.25, abs=1e-7)        # strong duality: L(p) = bound
    assert m.expectation(x**2) == pytest.approx(1.5, abs=3e-4)       # measured 7.5e-5 (sqrt of the gap)
    assert m.expectation(x) == pytest.approx(0.0, abs=1e-7)
    assert m.moment((4,)) == pytest.approx(2.25, abs=5e-4)
    with pytest.raises(sd.InputError, match="x\\^5"):
        m.moment((5,))


@pytest.mark.parametrize("backend,solver", [("direct", "CLARABEL"), ("cvxpy", "CLARABEL"), ("cvxpy", "CVXOPT")])
def test_six_hump_camel_two_global_minimisers(xy, backend, solver):
    if solver == "CVXOPT":
        pytest.importorskip("cvxopt")
    x, y = xy
    p = 4 * x**2 - 2.1 * x**4 + x**6 / 3 + x * y - 4 * y**2 + 4 * y**4
    sol, g, con = lower_bound(p, backend=backend, solver=solver)
    assert sol.value(g) == pytest.approx(CAMEL_MIN, abs=1e-7)
    atoms = sol.minimizers(con, tol=1e-5)
    assert len(atoms) == 2 and atoms.weights == pytest.approx([0.5, 0.5], abs=1e-4)
    pts = atoms.points[np.argsort(atoms.points[:, 0])]
    assert pts == pytest.approx(np.array([-CAMEL_POINT, CAMEL_POINT]), abs=1e-4)      # 1.7e-5, 4e-5
    assert p(pts) == pytest.approx([CAMEL_MIN] * 2, abs=1e-8)
    assert sol.moments(con).expectation(p) == pytest.approx(CAMEL_MIN, abs=1e-6)


def test_min_x_on_the_unit_disc_is_attained_at_minus_one_zero():
    prog, g, con = disc_minimum()
    sol = prog.solve()
    assert sol.value(g) == pytest.approx(-1.0, abs=1e-7)
    atoms = sol.minimizers(con)
    assert atoms.vars == ("x", "y") and atoms.points == pytest.approx(np.array([[-1.0, 0.0]]), abs=1e-6)
    assert atoms.weights == pytest.approx([1.0], abs=1e-6)


def test_points_are_as_accurate_as_the_solve(xy):
    """Atoms carry about the square root of the solver's gap: 8e-8 at tolerances 1e-11."""
    x, _ = xy
    tight = {"tol_gap_abs": 1e-11, "tol_gap_rel": 1e-11, "tol_feas": 1e-11}
    sol, _, con = lower_bound(x**4 - 3 * x**2 + 2, **tight)
    assert np.sort(sol.minimizers(con).points[:, 0]) == pytest.approx([-np.sqrt(1.5), np.sqrt(1.5)], abs=1e-6)


def test_a_circle_of_minimisers_is_not_flat_and_gives_no_points(xy):
    x, y = xy
    sol, g, con = lower_bound((x**2 + y**2 - 1) ** 2)
    assert sol.value(g) == pytest.approx(0.0, abs=1e-7)
    m = sol.moments(con)
    assert m.expectation(x**2 + y**2) == pytest.approx(1.0, abs=1e-4)     # supported on the circle
    with pytest.raises(sd.NoAtomsError, match="not flat: rank 5 .* 3 on degree <= 1"):
        sol.minimizers(con)


def test_motzkin_no_bound_and_no_invented_points(xy):
    x, y = xy
    motzkin = x**4 * y**2 + x**2 * y**4 + 1 - 3 * x**2 * y**2
    with pytest.raises(sd.InfeasibleError):                      # M - g is SOS for no g
        lower_bound(motzkin)[0].value(sd.Polynomial.constant(0.0))
    sol, g, con = lower_bound((x**2 + y**2 + 1) * motzkin)
    assert sol.value(g) == pytest.approx(0.0, abs=1e-6)
    with pytest.raises(sd.NoAtomsError, match="not in the Gram basis"):   # the Newton basis lacks x^2
        sol.minimizers(con)


def test_a_point_that_misses_the_bound_is_refused(xy):
    x, _ = xy
    sol, _, con = lower_bound(x**4 - 3 * x**2 + 2)
    atoms = sol.moments(con).atoms()
    residual = sol.value(con.source) + 0.01                      # pretend the bound were 0.01 lower
    with pytest.raises(sd.NoAtomsError, match="attains the bound"):
        check_atoms(atoms, residual, tol=1e-6)
    with pytest.raises(sd.NoAtomsError, match=">= 0"):           # and one outside x >= 2
        check_atoms(atoms, sol.value(con.source), ineqs=[x - 2], tol=1e-6)


def test_duals_are_checked_before_use():
    basis = np.array([[0], [1], [2]])
    hankel = np.array([[1.0, 0.0, 2.0], [0.0, 2.0, 0.0], [2.0, 0.0, 5.0]])   # moments 1, 0, 2, 0, 5
    m = moments_from_dual(("x",), basis, 3.0 * hankel)                         # scale removed: y_0 = 1
    assert m.values == pytest.approx([1, 0, 2, 0, 5]) and m.rank() == 3
    with pytest.raises(sd.UnverifiedSolutionError, match="not PSD"):
        moments_from_dual(("x",), basis, np.diag([1.0, -1.0, 1.0]))
    bad = hankel.copy()
    bad[1, 1] = 3.0                                    # PSD, but y_2 read as 3 here and as 2 at (0, 2)
    with pytest.raises(sd.UnverifiedSolutionError, match="not a moment matrix: .* by 0.5 "):
        moments_from_dual(("x",), basis, bad)
    with pytest.raises(sd.UnverifiedSolutionError, match="zero"):
        moments_from_dual(("x",), basis, np.zeros((3, 3)))


def test_extraction_recovers_planted_atoms_exactly():
    xs = np.array([[0.5, -1.0], [-2.0, 0.25], [1.5, 1.5]])
    w = np.array([0.2, 0.3, 0.5])
    basis = np.array([[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2]])
    Z = np.prod(xs[:, None, :] ** basis[None], axis=2)
    atoms = extract_atoms(("x", "y"), basis, (Z.T * w) @ Z)
    order = np.argsort(atoms.points[:, 0])
    assert atoms.points[order] == pytest.approx(xs[np.argsort(xs[:, 0])], abs=1e-9)
    assert atoms.weights[order] == pytest.approx(w[np.argsort(xs[:, 0])], abs=1e-9)


def test_moments_need_a_psd_scalar_constraint_and_an_objective(xy):
    x, _ = xy
    prog = sd.SOSProgram()
    con = prog.add_sos(x**2 + 1, cone="sdsos")
    sol = prog.solve()
    with pytest.raises(sd.InputError, match="cone 'sdsos'"):
        sol.moments(con)
    prog = sd.SOSProgram()
    con = prog.add_sos(x**2 + 1)                                  # feasibility only: zero dual
    with pytest.raises(sd.InputError, match="no objective"):
        prog.solve().moments(con)

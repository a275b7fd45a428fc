"""Rigorous bounds: the reported bound is proven by exact arithmetic, on the right side of the
known optimum and within 1e-6 of it (../shared/reference/sos-known-answers.md)."""
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sosdyn as sd
from sosdyn.sos import examples
from sosdyn.sos.gram import matrix_to_svec

x, y = sd.variables("x y")
(X,) = sd.variables("x")


def lower_bound(p, **kw):
    prog = sd.SOSProgram("lower bound")
    g = prog.new_var()
    prog.add_sos(p - g, **kw)
    prog.maximize(g)
    return prog


def user_basis():
    prog = sd.SOSProgram("user basis")
    g = prog.new_var()
    prog.add_sos(X**4 + 4 - g, basis=[X**2])
    prog.maximize(g)
    return prog


MOTZKIN = x**4 * y**2 + x**2 * y**4 + 1 - 3 * x**2 * y**2


KNOWN = {
    "chebyshev (5)": (lambda: examples.chebyshev()[0], Fraction(128)),
    "probability bound (6)": (lambda: examples.probability_bound()[0], Fraction(1, 37)),
    "user basis (11)": (user_basis, Fraction(4)),
    "two global minima": (lambda: lower_bound(X**4 - 3 * X**2 + 2), Fraction(-1, 4)),
    "Motzkin times 1 + x^2 + y^2 (9)": (lambda: lower_bound((x**2 + y**2 + 1) * MOTZKIN), Fraction(0)),
    "matrix, supremum 2": (lambda: examples.matrix_program()[0], Fraction(2)),
}


@pytest.mark.parametrize("name", list(KNOWN))
def test_proven_bound_is_on_the_right_side_of_the_known_optimum(name):
    make, optimum = KNOWN[name]
    prog = make()
    sol = prog.solve(rigorous=True)
    bound = sol.bound
    sense = prog.objective[0]
    proven = Fraction(bound.proven)
    assert proven <= optimum if sense == "max" else proven >= optimum
    assert abs(float(proven - optimum)) <= 1e-6 * max(1.0, abs(float(optimum)))
    assert sol.objective == bound.proven and bound.gap == abs(bound.solver_value - bound.proven)
    assert sol.verify().passed and all(m >= 0 for m in bound.margins.values())


def test_floudas_degree_8_bound_is_below_the_true_minimum():
    # Clarabel's own answer is above the minimum (not a lower bound); the proven one is below
    prog, g = examples.floudas(8)
    sol = prog.solve(rigorous=True)
    true_min = examples.floudas_minimum()
    assert sol.bound.proven <= true_min
    assert sol.bound.proven >= true_min * (1 + 1e-5)          # within 1e-5 relative (2e-6 with Clarabel 0.11.1)
    assert sol.value(g) == sol.objective == sol.bound.proven  # every number is read at the proof


def test_a_certificate_that_passes_the_tolerant_check_is_backed_off_to_the_truth(forged):
    # t = 2 + 5e-8 with the Gram's y_i^2 entries at -5e-8: verify() passes (within tolerance),
    # the claim t > 2 is false; the number handed out is proven (<= 2), the rigorous one exactly 2
    prog, t, con = examples.matrix_program()
    Q = prog.solve().gram_matrix(con)
    Q[np.abs(Q.diagonal()) < 1e-6, np.abs(Q.diagonal()) < 1e-6] = -5e-8
    sol = forged(prog, [(t, [2 + 5e-8]), (con.psd, matrix_to_svec(Q))])
    assert sol.verify().passed and sol.values_of(t.ids)[0] > 2
    assert 2 - 1e-6 <= sol.value(t) <= 2
    assert sol.rigorous_bound().proven == 2.0


def test_rigorous_bound_refuses_what_it_cannot_prove(forged):
    prog = sd.SOSProgram()
    a = prog.new_var()
    prog.add_sos(a * x**2 + 1)
    prog.minimize(sd.sum_squares([a - 1]))
    with pytest.raises(sd.UnverifiedSolutionError, match="affine objective"):
        prog.solve(rigorous=True).objective
    # an unverified answer is not proven either
    prog2 = sd.SOSProgram("forged")
    con = prog2.add_nonneg_on(X**2 - 0.25, ineqs=[1 - X**2], degree=2)
    bad = forged(prog2, [(con.multipliers[0].psd, [-0.25])])
    with pytest.raises(sd.UnverifiedSolutionError, match="independent check"):
        bad.rigorous_bound()


def test_feasibility_certificates_are_proven_exactly():
    sol = examples.moore_greitzer(0.77).solve(rigorous=True)
    assert sol.bound.proven is None and len(sol.bound.margins) == 2
    assert all(m > 0 for m in sol.bound.margins.values())


@settings(max_examples=4, deadline=None, derandomize=True)
@given(st.integers(0, 10**6), st.sampled_from(["global", "disk"]))
def test_proven_lower_bounds_hold_at_every_sampled_point(random_program, seed, kind):
    prog, g, p, disk = random_program(seed, kind)
    bound = prog.solve(rigorous=True).bound
    pts = np.random.default_rng(seed).uniform(-3, 3, size=(20_000, 2))
    if kind == "disk":
        pts = pts[disk(pts, ["x", "y"]) >= 0]
    vals = p(pts, ["x", "y"])
    assert bound.proven <= bound.solver_value + 1e-9
    assert vals.min() >= bound.proven - 1e-12 * max(1.0, np.abs(vals).max())


def test_updating_a_putinar_constraint_keeps_its_multipliers_and_the_proof():
    # q >= 1/2 on [4, 5] instead of q >= 1: the optimum halves to 1/74 (the problem is linear in it)
    prog, (a, b, c) = examples.probability_bound()
    con = prog.sos_constraints[1]
    (x_,) = sd.variables("x")
    con.update(a + b * x_ + c * x_**2 - 0.5)
    assert len(con.multipliers) == 1
    bound = prog.solve(rigorous=True).bound
    assert Fraction(bound.proven) >= Fraction(1, 74)
    assert bound.proven - 1 / 74 <= 1e-6 / 74

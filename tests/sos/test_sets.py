"""Putinar / S-procedure: BasicSet, per-constraint degrees, preorder products, free multipliers,
minimize_on. Every expected value is derived by hand in the test."""
import math

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import BasicSet, minimize_on
from sosdyn.sos.sets import degree_bounds, preorder


def test_min_xy_on_the_box_is_minus_one_at_degree_two():
    # x y + 1 = (x + y)^2 / 2 + (1 - x^2) / 2 + (1 - y^2) / 2: the S-procedure is exact
    x, y = sd.variables("x y")
    lb = minimize_on(x * y, BasicSet.box("x y", -1, 1), degree=2)
    assert lb.value == pytest.approx(-1.0, abs=1e-6)
    assert [len(m.basis) for m in lb.constraint.multipliers] == [1, 1]     # constant multipliers


def test_s_procedure_on_an_ellipse():
    # min x + y on x^2/4 + y^2 <= 1 is -sqrt(4 + 1) (support function of the ellipse)
    x, y = sd.variables("x y")
    K = BasicSet(ineqs=[1 - x**2 / 4 - y**2])
    assert K.contains([[2, 0], [0, 1], [1.5, 0.7]]).tolist() == [True, True, False]
    lb = minimize_on(x + y, K, degree=2)
    assert lb.value == pytest.approx(-math.sqrt(5), abs=1e-6)


def test_free_multiplier_for_an_equality():
    # max x y on x + y = 1 is 1/4: 1/4 - x y = (x - y)^2 / 4 + (1 + x + y)(1 - x - y) / 4,
    # so lambda = -(1 + x + y) / 4 must be a free polynomial of degree 1
    x, y = sd.variables("x y")
    lb = minimize_on(-x * y, BasicSet(eqs=[x + y - 1]), degree=2)
    assert lb.value == pytest.approx(-0.25, abs=1e-6)
    lam = lb.constraint.eq_multipliers[0].poly
    assert lam.nterms == 3                                                  # 1, x, y: degree 1


def test_products_certify_at_a_lower_degree():
    # x y >= 0 on {x >= 0, y >= 0}: with the product g0 g1 = x y it is sigma_01 = 1 (degree 2);
    # with single terms, x y - a x - b y - gamma is never SOS (its quadratic part is indefinite)
    x, y = sd.variables("x y")
    K = BasicSet(ineqs=[x, y])
    lb = minimize_on(x * y, K, degree=2, products=True)
    assert lb.value == pytest.approx(0.0, abs=1e-6)
    assert [m.constraint.degree for m in lb.constraint.multipliers] == [1, 1, 2]
    with pytest.raises(sd.InfeasibleError):
        minimize_on(x * y, K, degree=2)


def test_per_constraint_degrees_list_and_dict():
    # min y on the disk cut by x >= 0 is -1: y + 1 = (x^2 + (y + 1)^2) / 2 + (1 - x^2 - y^2) / 2
    x, y = sd.variables("x y")
    K = BasicSet(ineqs=[1 - x**2 - y**2, x])
    prog = sd.SOSProgram()
    g = prog.new_var()
    con = prog.add_nonneg_on(y - g, K, degree=[4, 2])
    prog.maximize(g)
    assert prog.solve().value(g) == pytest.approx(-1.0, abs=1e-6)
    # bound 4 on the disk's product: sigma of degree 2 (1, x, y); bound 2 on x: degree 0
    assert [len(m.basis) for m in con.multipliers] == [3, 1]
    con = sd.SOSProgram().add_nonneg_on(y, K, degree={1: 3})
    assert [len(m.basis) for m in con.multipliers] == [1, 3]     # default 2 for g0; 3 for g1: degree 2
    assert degree_bounds({1: 3}, 2, 2) == [2, 3]
    with pytest.raises(sd.InputError, match="2 constraints"):
        degree_bounds([2, 2, 2], 2, 2)
    with pytest.raises(sd.PolynomialError, match="Try: degree >= 2"):
        sd.SOSProgram().add_nonneg_on(y, K, degree=[1, 2])


def test_bounds_in_probability_on_boxes():
    # known answer 6: min a + b + 1.25 c, q = a + b x + c x^2 >= 0 on [0, 5], q - 1 >= 0 on [4, 5]: 1/37
    (x,) = sd.variables("x")
    prog = sd.SOSProgram()
    a, b, c = (prog.new_var() for _ in range(3))
    q = a + b * x + c * x**2
    prog.add_nonneg_on(q, BasicSet.box([x], 0, 5), degree=2)
    prog.add_nonneg_on(q - 1, BasicSet.box([x], 4, 5), degree=2)
    prog.minimize(a + b + 1.25 * c)
    assert prog.solve().objective == pytest.approx(1 / 37, abs=1e-6)


def test_lasserre_hierarchy_on_the_simplex():
    # min x y on the simplex {x, y >= 0, x + y <= 1} is 0 (on the edges). Putinar's bounds are
    # valid (<= 0) and nondecreasing in the degree; degree 2 has only constant multipliers, so
    # x y - gamma - sum c_i g_i would need an indefinite quadratic part: infeasible. The
    # product x * y of two constraints certifies 0 at degree 2 (the preorder).
    x, y = sd.variables("x y")
    K = BasicSet(ineqs=[x, y, 1 - x - y])
    with pytest.raises(sd.InfeasibleError):
        minimize_on(x * y, K, degree=2)
    bounds = [minimize_on(x * y, K, degree=d).value for d in (4, 6, 8)]
    assert all(b <= 1e-7 for b in bounds)
    assert bounds[0] < -1e-3 and bounds[0] <= bounds[1] + 1e-9 <= bounds[2] + 2e-9
    assert minimize_on(x * y, K, degree=2, products=2).value == pytest.approx(0.0, abs=1e-6)


def test_s_lemma_on_the_disk():
    # min -(x - 1)^2 - (y - 1)^2 on the unit disk = -(1 + sqrt 2)^2 at -(1, 1)/sqrt 2 (by hand:
    # the farthest disk point from (1, 1)); degree 2 is exact (the S-lemma: one quadratic
    # constraint, a nonconvex quadratic objective)
    x, y = sd.variables("x y")
    f = -(x - 1) ** 2 - (y - 1) ** 2
    lb = minimize_on(f, BasicSet.ball("x y"), degree=2)
    assert lb.value == pytest.approx(-(1 + math.sqrt(2)) ** 2, abs=1e-6)


def test_rigorous_bound_through_minimize_on():
    x, y = sd.variables("x y")
    lb = minimize_on(x * y, BasicSet.box("x y", -1, 1), degree=2, rigorous=True)
    assert lb.solution.bound.proven
    assert -1.0 - 1e-6 <= lb.value <= -1.0


def test_set_inputs_are_checked():
    x, y = sd.variables("x y")
    with pytest.raises(sd.InputError, match="inside the BasicSet"):
        sd.SOSProgram().add_nonneg_on(x**2, BasicSet(ineqs=[x]), eqs=[y])
    with pytest.raises(sd.InputError, match="list of polynomials"):
        sd.SOSProgram().add_nonneg_on(x**2, 1 - x**2)
    with pytest.raises(sd.PolynomialError, match="numeric Polynomial"):
        BasicSet(ineqs=["x"])
    with pytest.raises(sd.InputError, match="global bound"):
        minimize_on(x**2, degree=4)
    assert [S for S, _ in preorder([x, y, 1 - x], 2)] == [(0,), (1,), (2,), (0, 1), (0, 2), (1, 2)]
    assert len(preorder([x, y, 1 - x], True)) == 7
    K = BasicSet(ineqs=[x]) & BasicSet(eqs=[y])
    assert K.contains(np.array([[1.0, 0.0], [1.0, 0.5], [-1.0, 0.0]])).tolist() == [True, False, False]

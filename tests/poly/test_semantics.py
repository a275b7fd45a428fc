"""Polynomial semantics (issue 15, item 6): evaluation by name or in ``p.vars`` order (never by
operand order), equality and hashing by value, decision variables printed by name."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import Polynomial, allocate
from sosdyn.poly.decision import decision_name
from sosdyn.poly.canonical import merged_vars, natural_key


@pytest.fixture
def xy():
    return sd.variables("x y")


def test_operand_order_never_decides_the_column_order(xy):
    x, y = xy
    q = y + x**2
    assert q.vars == ("x", "y") == (x**2 + y).vars
    assert q([[1.0, 2.0]]) == pytest.approx([3.0])          # x = 1, y = 2: 1 + 2 (not 2^2 + 1 = 5)
    assert (y * x**3).vars == ("x", "y")
    x2, x10 = sd.variables("x2 x10")
    assert (x10 + x2).vars == ("x2", "x10")                  # natural order, not "x10" < "x2"


def test_evaluation_by_name(xy):
    x, y = xy
    q = y + x**2
    assert q({"y": 2.0, "x": 1.0}) == pytest.approx([3.0])
    assert q({"x": [1.0, 2.0, 3.0], "y": 0.5}) == pytest.approx([1.5, 4.5, 9.5])   # a scalar broadcasts
    with pytest.raises(sd.PolynomialError, match=r"missing \['y'\].*Try"):
        q({"x": 1.0})
    with pytest.raises(sd.PolynomialError, match="equally many"):
        q({"x": [1.0, 2.0], "y": [1.0, 2.0, 3.0]})
    with pytest.raises(sd.PolynomialError, match="NaN"):
        q({"x": np.nan, "y": 1.0})
    assert q(np.array([[1.0, 2.0]]), vars=("y", "x")) == pytest.approx([5.0])      # y = 1, x = 2


def test_a_declared_order_is_kept_when_it_covers_the_other_operand(xy):
    x, y = xy
    p = (x + y).with_vars(("y", "x"))
    assert (p + x).vars == ("y", "x") == (x + p).vars
    assert merged_vars(("y", "x"), ("x", "y")) == ("x", "y")      # same set, two orders: natural
    assert sorted(["x10", "x2", "x1", "y"], key=natural_key) == ["x1", "x2", "x10", "y"]


def test_equality_is_by_value(xy):
    x, y = xy
    assert (x + 1) ** 2 == x**2 + 2 * x + 1
    assert not ((x + 1) ** 2 == x**2 + 1)
    assert (x + 1) ** 2 != x**2 + 1
    assert x + y == (y + x).with_vars(("y", "x"))
    assert Polynomial.constant(3.0) == 3 and x - x == 0
    assert (x == "x") is False                                   # other types: not equal, no error


def test_hash_agrees_with_equality(xy):
    x, y = xy
    a, b = x * y + 2.0, (2.0 + y * x).with_vars(("y", "x"))
    assert a == b and hash(a) == hash(b)
    assert len({a, b, x + y, y + x, x - x, Polynomial.constant(0.0)}) == 3
    assert {a: "found"}[b] == "found"
    assert hash(-0.0 * x + 1) == hash(Polynomial.constant(1.0))


def test_decision_variables_compare_and_print_by_name(xy):
    x, _ = xy
    prog = sd.SOSProgram()
    g = prog.new_var(name="g")
    c = prog.new_var(3, name="c")
    assert repr(g) == "g" and repr(c[1, 0]) == "c[1]"
    assert repr(2 * g - 3 * c[2, 0] * x + 1 - x**2) == "(1 + 2*g) - 3*c[2]*x - x^2"
    assert g == g + 0 and g != 2 * g and g != c[0, 0]
    assert {str(s) for s in sd.to_sympy(g * x + 1).free_symbols} == {"g", "x"}
    (unnamed,) = allocate(1)
    assert decision_name(unnamed) == f"d{unnamed}"


def test_to_sympy_never_merges_a_decision_name_with_a_variable(xy):
    x, _ = xy
    prog = sd.SOSProgram()
    clash = prog.new_var(name="x")
    expr = sd.to_sympy(clash * x)
    assert {str(s) for s in expr.free_symbols} == {"x", f"d{int(clash.ids[0])}"}

"""sympy I/O (sosdyn.poly.sympy_io): from_sympy never evaluates a string as code, parses
polynomial strings exactly, and refuses bad coefficients and huge expansions before expanding."""

import pytest
import sympy

import sosdyn as sd

x, y = sd.variables("x y")
X, Y = sympy.symbols("x y")


@pytest.mark.parametrize("payload", [
    "__import__('os').system('touch {marker}')",
    "open('{marker}', 'w').write('x')",
    "().__class__.__bases__[0].__subclasses__() or open('{marker}', 'w')",
    "(lambda: open('{marker}', 'w'))()",
    "[open('{marker}', 'w') for _ in (1,)]",
    "x if open('{marker}', 'w') else x",
    "exec(\"open('{marker}', 'w')\")",
])
def test_a_malicious_string_is_never_evaluated(tmp_path, payload):
    marker = tmp_path / "pwned"
    with pytest.raises(sd.PolynomialError, match="not a polynomial|not allowed"):
        sd.from_sympy(payload.format(marker=marker), ["x"])
    assert not marker.exists()


def test_an_object_whose_str_is_code_is_not_evaluated(tmp_path):
    marker = tmp_path / "pwned"

    class Sneaky:                       # sympify(obj) would parse and evaluate str(obj)
        def __str__(self):
            return f"__import__('os').system('touch {marker}')"

    with pytest.raises(sd.PolynomialError, match="sympy expression or a polynomial string"):
        sd.from_sympy(Sneaky(), ["x"])
    assert not marker.exists()


def test_polynomial_strings_are_parsed_exactly():
    t8 = sd.from_sympy("128*x**8 - 256*x**6 + 160*x**4 - 32*x**2 + 1", ["x"])
    assert t8.allclose(sd.from_sympy(128 * X**8 - 256 * X**6 + 160 * X**4 - 32 * X**2 + 1, ["x"]), atol=0)
    p = sd.from_sympy("x^2/4 - (y - 1)**2 * 2.5e-1 + -(-x) * +y", ["x", "y"])
    assert p.allclose(x**2 / 4 - (y - 1) ** 2 * 0.25 + x * y, atol=1e-15)
    assert sd.from_sympy(" + ".join(f"{i}*x**{i % 7}" for i in range(1000)), ["x"]).nterms == 7


@pytest.mark.parametrize("text, match", [
    ("sin(x)", "not a polynomial"),
    ("x/(x + 1)", "division by the non-constant"),
    ("x**-1", "non-negative integer"),
    ("x**0.5", "non-negative integer"),
    ("x**y", "non-negative integer"),
    ("2j*x", "complex"),
    ("q*x", "not in vars"),
    ("x**10**6", "degree 1000000"),
    ("2**10**6", "infinite|above 1e\\+150"),
    ("1e300*x**4 + 1", "above 1e\\+150"),
    ("x +", "cannot parse"),
    ("(" * 500 + "x" + ")" * 500, "cannot parse|nested"),
    ("x" * (10**6 + 1), "longer than"),
])
def test_bad_polynomial_strings_raise_typed_errors(text, match):
    with pytest.raises(sd.PolynomialError, match=match):
        sd.from_sympy(text, ["x", "y"])


@pytest.mark.parametrize("expr, match", [
    (X**2 + sympy.I * X, "complex"),
    (X**2 + sympy.oo, "not finite"),
    (X**2 + sympy.nan, "not finite"),
    (sympy.Float(1e300) * X**4 + 1, "above 1e\\+150"),
])
def test_bad_sympy_coefficients_raise_typed_errors(expr, match):
    with pytest.raises(sd.PolynomialError, match=match):
        sd.from_sympy(expr, ["x"])


def test_huge_sympy_expansions_are_refused_before_sympy_expands_them(monkeypatch):
    def refuse(*args, **kw):
        raise AssertionError("sympy.expand was called")
    monkeypatch.setattr(sympy, "expand", refuse)
    with pytest.raises(sd.PolynomialError, match="degree up to 1000000"):
        sd.from_sympy((X + 1) ** (10**6), ["x"])
    a = sympy.symbols("a0:12")
    with pytest.raises(sd.ResourceLimitError, match="expanding a sympy expression"):
        sd.from_sympy(sum(a) ** 40, [str(s) for s in a])        # C(51, 40) ~ 4.8e10 terms
    monkeypatch.undo()
    assert sd.from_sympy((X + Y + 1) ** 30, ["x", "y"]).nterms == 496  # C(32, 2)

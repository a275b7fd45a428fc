"""The Python fast path of small polynomials (sosdyn.poly.smallterms) against the array path.

Every operator is computed twice on the same operands: with the fast path (the default for small
operands, smallterms.fits) and with it switched off (fits always False sends everything to numpy);
the arrays must agree: the same exponent rows in the same order, the same decision ids, the same
coefficients up to rounding (numpy groups a sum of three or more like terms differently).
"""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import PolynomialError
from sosdyn.poly import Polynomial, match_rows, monomials_up_to, smallterms, unique_rows
from sosdyn.poly import monomials as mono


def arrays(p):
    return p.vars, p.exps.tolist(), p.coef.tolist(), p.ids.tolist()


def both(fn, monkeypatch):
    """(fast-path result, array-path result) of fn()."""
    fast = fn()
    with monkeypatch.context() as m:
        m.setattr(smallterms, "fits", lambda *args: False)
        slow = fn()
    return fast, slow


def random_poly(rng, vars, ids, terms=5, deg=3):
    exps = rng.integers(0, deg + 1, size=(terms, len(vars)))
    coef = rng.integers(-4, 5, size=(terms, 1 + len(ids))) * rng.choice([1.0, 0.5, 1e-3], size=(terms, 1))
    return Polynomial(vars, exps, coef, ids)


@pytest.mark.parametrize("seed", range(12))
def test_operators_agree_with_the_array_path(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    a = random_poly(rng, ("x", "y"), [3, 7])
    b = random_poly(rng, ("y", "z"), [7, 9] if seed % 2 else [])
    c = random_poly(rng, ("x",), [])
    cases = [lambda: a + b, lambda: a - b, lambda: b - a, lambda: a * c, lambda: c * b, lambda: 2.5 * a,
             lambda: a - a, lambda: c**3, lambda: (c + 1) ** 2, lambda: -b, lambda: 3 - a, lambda: a + 1e-3]
    for k, fn in enumerate(cases):
        fast, slow = both(fn, monkeypatch)
        assert (fast.vars, fast.exps.tolist(), fast.ids.tolist()) == (slow.vars, slow.exps.tolist(), slow.ids.tolist())
        np.testing.assert_allclose(fast.coef, slow.coef, rtol=1e-14, atol=0, err_msg=f"{seed}, {k}")


def test_known_results():
    x, y = sd.variables("x y")
    p = (x + y) ** 2 - x**2
    assert arrays(p) == (("x", "y"), [[0, 2], [1, 1]], [[1.0], [2.0]], [])
    assert (x - x).nterms == 0 and (x - x).coef.shape == (0, 1)
    prog = sd.SOSProgram()
    g = prog.new_var()
    q = (x**2 - g) + g                                    # the decision id cancels: it is dropped
    assert arrays(q) == (("x",), [[2]], [[1.0]], [])
    assert arrays(Polynomial.constant(0.0, ("x",))) == (("x",), [], [], [])


def test_overflow_underflow_and_degree():
    (x,) = sd.variables("x")
    with pytest.raises(PolynomialError, match="infinite"):
        (1e100 * x) ** 4                                  # 1e400: an overflow, refused
    with pytest.raises(PolynomialError, match="above 1e"):
        1e149 * (100 * x)
    assert (1e-200 * x * 1e-200).nterms == 0              # an underflow to 0 drops the term
    with pytest.raises(PolynomialError, match="a product has degree 1200"):
        x**600 * x**600
    with pytest.raises(PolynomialError, match=r"a power p\*\*1001"):
        x**1001
    with pytest.raises(PolynomialError, match="NaN"):
        x * float("nan")


def test_unique_and_match_rows_small_and_large_agree(monkeypatch):
    rng = np.random.default_rng(1)
    for m in (0, 1, 5, 40):
        E = rng.integers(0, 4, size=(m, 3))
        fast_u, fast_inv = unique_rows(E)
        Q = rng.integers(0, 4, size=(7, 3))
        fast_m = match_rows(fast_u, Q)
        with monkeypatch.context() as mp:
            mp.setattr(mono, "SMALL_ROWS", -1)
            slow_u, slow_inv = unique_rows(E)
            slow_m = match_rows(slow_u, Q)
        assert fast_u.tolist() == slow_u.tolist() and fast_inv.tolist() == slow_inv.tolist()
        assert fast_m.tolist() == slow_m.tolist()
        assert (fast_u[fast_inv] == E).all()


def test_cached_monomials_are_fresh_copies_and_still_checked():
    a = monomials_up_to(2, 2)
    assert a.tolist() == [[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2]]
    a[0, 0] = 9                                            # the caller's copy, not the cache
    assert monomials_up_to(2, 2)[0].tolist() == [0, 0]
    with sd.limits(max_bytes=100), pytest.raises(sd.ResourceLimitError):
        monomials_up_to(2, 2)                              # a cached answer is still size-checked


def test_asymmetry_entry_by_entry_equals_the_term_sort(monkeypatch):
    from sosdyn.poly import matrix as pm
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    g = prog.new_var()
    mats = [sd.PolyMatrix([[x**2 + 1, x * y - 3], [x * y, 2 * y**2]]),
            sd.PolyMatrix([[x + g, 1e3 * x * y, g], [1e3 * x * y + 1e-13, y, 0], [g, 0, 1]]),
            sd.PolyMatrix([[x, y], [y, x]])]
    fast = [M.asymmetry() for M in mats]
    monkeypatch.setattr(pm, "SMALL_SIDE", 0)
    slow = [M.asymmetry() for M in mats]
    for f, s in zip(fast, slow):
        np.testing.assert_allclose(f, s, rtol=1e-15, atol=0)
    assert fast[0][0, 1] == pytest.approx(1.0) and fast[2].max() == 0.0
    assert fast[1][0, 1] == pytest.approx(1e-16)            # 1e-13 over the largest coefficient 1e3

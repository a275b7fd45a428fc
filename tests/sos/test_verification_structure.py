"""The cached Gram structure of the independent check (issue 14): same numbers as a fresh
check, remembered per (monomials, basis), and no laxer after a re-solve with new weights."""
from dataclasses import replace

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos.gram import matrix_to_svec
from sosdyn.sos.verification import (cached_gram_structure, check_gram, check_gram_values,
                                     gram_structure)

(X,) = sd.variables("x")
BASIS = np.array([[0], [1], [2]])                     # z = (1, x, x^2)


def test_structure_places_every_product_and_monomial():
    p = Polynomial(("x",), [[0], [4], [5]], [1.0, 1.0, 2.0])          # 1 + x^4 + 2 x^5
    s = gram_structure(p.exps, BASIS)
    # U = {1, x, x^2, x^3, x^4, x^5}: x^5 is no product z_i z_j
    assert s.in_gram.tolist() == [True, True, True, True, True, False]
    assert s.p_at.tolist() == [0, 4, 5]
    assert s.pair_at.reshape(3, 3).tolist() == [[0, 1, 2], [1, 2, 3], [2, 3, 4]]


def test_exact_certificate_and_known_residuals():
    p = Polynomial(("x",), [[0], [2], [4]], [1.0, -2.0, 1.0])         # (x^2 - 1)^2
    v = np.array([-1.0, 0.0, 1.0])
    ok = check_gram("p", "sos", p, BASIS, np.outer(v, v))
    assert ok.passed and ok.residual == 0.0 and abs(ok.min_eig) < 1e-15
    off = check_gram("p", "sos", p, BASIS, np.outer(v, v) + 0.25 * np.eye(3))
    # z^T (Q + I/4) z - p = (1 + x^2 + x^4) / 4: residual 0.25 relative to max|coef p| = 2
    assert not off.passed and off.residual == 0.25 and off.rel_residual == 0.125
    q = Polynomial(("x",), [[0], [2], [4], [5]], [1.0, -2.0, 1.0, 1e-9])
    tiny = check_gram("q", "sos", q, BASIS, np.outer(v, v) + 0.5 * np.eye(3))
    assert np.isclose(tiny.min_eig, 0.5) and tiny.margin == -np.inf   # x^5 cannot come from z^T Q z
    assert not tiny.proven and not tiny.passed


def test_values_path_equals_polynomial_path():
    rng = np.random.default_rng(3)
    B = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 0]])
    Q = rng.normal(size=(5, 5))
    Q = Q @ Q.T
    exps = np.array([[0, 0], [2, 0], [1, 1], [3, 1], [4, 0], [0, 3]])
    p = Polynomial(("x", "y"), exps, rng.normal(size=6))
    a = check_gram("p", "sos", p, B, Q)
    b = check_gram_values("p", "sos", p.coef[:, 0], cached_gram_structure(p.exps, B), Q)
    assert replace(a, proven=None, reason=b.reason) == b and a.residual > 0.1 and not a.passed


def test_structure_is_remembered_per_array():
    p = Polynomial(("x",), [[0], [4]], [1.0, 1.0])
    s1 = cached_gram_structure(p.exps, BASIS)
    assert cached_gram_structure(p.exps, BASIS) is s1
    assert not (s1.p_at.flags.writeable or s1.pair_at.flags.writeable or s1.in_gram.flags.writeable)
    other = cached_gram_structure(p.exps.copy(), BASIS)       # equal content, another array
    assert other is not s1 and np.array_equal(other.pair_at, s1.pair_at)


def _family():
    prog = sd.SOSProgram("family")
    a = prog.new_var()
    T1 = PolyMatrix([[X**2 + 1, X], [X, 1 + 0 * X]])
    T2 = PolyMatrix([[a * 1.0 + 0 * X, 0 * X], [0 * X, a * 1.0 + 0 * X]])
    con = prog.add_sos_matrix_family([T1, T2], [1.0, 1.0])
    prog.minimize(a)
    return prog, con, a


def test_reweighted_family_is_checked_again(forged):
    prog, con, a = _family()
    sol = prog.solve()
    assert sol.verified and sol.verify().passed
    con.set_weights([1.0, 0.5])                         # same structure, new numbers
    sol2 = prog.solve()
    assert sol2.verified
    # a forged Gram matrix for the new weights: right support, indefinite
    n = con.psd.size
    Q = -np.eye(n)
    bad = forged(prog, [(a, [0.0]), (con.psd, matrix_to_svec(Q))])
    report = bad.verify()
    assert not report.passed and report.min_eig == -1.0
    assert any(c.name == con.name and c.residual > 0.5 for c in report.failures)


def test_check_gram_refuses_a_decision_polynomial():
    prog = sd.SOSProgram("decision")
    a = prog.new_var()
    with pytest.raises(sd.PolynomialError, match="numeric polynomial.*Try"):
        check_gram("p", "sos", a * X**2 + 1.0, BASIS, np.eye(3))

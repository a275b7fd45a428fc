"""Gram matrices: coefficient matching reproduces random Gram polynomials; the exact machinery
of rigorous bounds (sosdyn.sos.gram)."""
from fractions import Fraction

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import sosdyn as sd
from sosdyn.poly import Polynomial, monomials_up_to
from sosdyn.sos.gram import (absorb_residual, exact_correction, exactly_psd, gram_form, positive_definite_int,
                             proven_min_eig)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(st.integers(0, 10_000), st.sampled_from([1, 2]))
def test_random_gram_polynomials_are_found_sos_and_reconstructed(seed, half_degree):
    """z^T Q z with Q PSD random must be SOS; the recovered Gram reproduces the polynomial."""
    rng = np.random.default_rng(seed)
    z = monomials_up_to(2, half_degree)
    L = rng.normal(size=(len(z), len(z)))
    Q = L @ L.T + 1e-3 * np.eye(len(z))
    p = Polynomial(("x", "y"), (z[:, None] + z[None]).reshape(-1, 2), Q.ravel())
    prog = sd.SOSProgram()
    con = prog.add_sos(p)
    sol = prog.solve()
    assert sol.usable
    Qr = sol.gram_matrix(con)
    B = con.basis.exps
    back = Polynomial(("x", "y"), (B[:, None] + B[None]).reshape(-1, 2), Qr.ravel())
    assert back.allclose(p, atol=1e-6 * np.abs(Q).max())


# ---------------------------------------------------------------------- the exact machinery
def test_proven_min_eig():
    F = np.vectorize(Fraction, otypes=[object])
    lb = proven_min_eig(F(np.array([[2.0, 1.0], [1.0, 2.0]])))
    assert 0.99 < lb <= 1.0                                   # lambda_min = 1
    assert proven_min_eig(F(np.array([[1.0, 1.0], [1.0, 1.0]]))) == 0.0   # singular: exact LDL^T
    tiny = np.array([[1.0, 1.0], [1.0, 1.0 - 2.0**-50]])     # det < 0 by 2^-50
    assert proven_min_eig(F(tiny)) is None and not exactly_psd(F(tiny))
    assert np.linalg.eigvalsh(tiny).min() > -1e-15            # floats alone cannot tell
    hilbert = np.array([[Fraction(1, i + j + 1) for j in range(8)] for i in range(8)], dtype=object)
    lb = proven_min_eig(hilbert)                              # lambda_min = 1.1e-10
    assert lb is not None and 0 < lb <= 1.2e-10


def test_positive_definite_int_is_sylvester():
    assert positive_definite_int(np.array([[2, -1, 0], [-1, 2, -1], [0, -1, 2]]))
    assert not positive_definite_int(np.array([[1, 2], [2, 1]]))
    assert not positive_definite_int(np.array([[1, 1], [1, 1]]))


def test_absorbed_residual_reproduces_the_polynomial_exactly():
    basis = np.array([[0], [1], [2]])
    Q = np.array([[Fraction(1), Fraction(0), Fraction(-1)], [Fraction(0), Fraction(1), Fraction(0)],
                  [Fraction(-1), Fraction(0), Fraction(2)]], dtype=object)
    target = {(0,): Fraction(1), (2,): Fraction(-1, 3), (4,): Fraction(2), (3,): Fraction(1, 7)}
    residual = {m: target.get(m, 0) - gram_form(basis, Q).get(m, 0) for m in set(target) | set(gram_form(basis, Q))}
    Q2, missing = absorb_residual(basis, Q, residual)
    assert missing is None
    assert {m: c for m, c in gram_form(basis, Q2).items() if c} == target
    assert absorb_residual(basis, Q, {(5,): Fraction(1)}) == (None, (5,))


def test_exact_correction_is_the_minimum_norm_solution():
    rows = [(Fraction(-1), {0: Fraction(1), 1: Fraction(1)})]           # d0 + d1 = 1
    delta = exact_correction(rows, {0: Fraction(0), 1: Fraction(0)})
    assert delta == {0: Fraction(1, 2), 1: Fraction(1, 2)}
    assert exact_correction(rows + rows, {0: Fraction(0), 1: Fraction(0)}) == delta   # dependent rows
    inconsistent = [(Fraction(-1), {0: Fraction(1)}), (Fraction(-2), {0: Fraction(1)})]
    assert exact_correction(inconsistent, {0: Fraction(0)}) is None

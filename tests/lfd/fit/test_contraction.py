"""G_k and M as numbers and as polynomial matrices: both agree, and known answers."""
import numpy as np
import pytest

from sosdyn.lfd.fit.contraction import (certificate_matrices, constant_index, contraction_degree, contraction_matrices,
                                    contraction_polymatrix, decision_fields, decision_metric, degree, eval_metric,
                                    field_exponents, field_jacobian, generalized_max_eig, margin_degree,
                                    metric_exponents, numeric_fields, numeric_metric, sample_states,
                                    sampled_eigenvalues, state_variables, symmetric_pairs, unit_fields, unit_metrics)
from sosdyn.poly import allocate, jacobian

RNG = np.random.default_rng(0)
FEXPS, MEXPS = field_exponents(2, 3), metric_exponents(2, 2)
C = RNG.normal(size=(2, 2, FEXPS.shape[0]))
W = RNG.normal(size=(2, 2, MEXPS.shape[0]))
W = W + W.transpose(1, 0, 2)


def test_numeric_G_equals_the_polynomial_matrix_at_random_points():
    Z = RNG.uniform(-2, 2, size=(50, 2))
    vars = state_variables(2)
    G = contraction_matrices(C, FEXPS, W, MEXPS, Z, 0.3)
    M = numeric_metric(W, MEXPS, vars)
    for k, f in enumerate(numeric_fields(C, FEXPS, vars)):
        np.testing.assert_allclose(G[:, k], contraction_polymatrix(f, M, vars, 0.3)(Z, vars), rtol=1e-10,
                                   atol=1e-10)


def test_linear_field_constant_metric_is_the_lyapunov_matrix():
    A = np.array([[-1.0, 4.0], [0.0, -1.0]])
    P = np.array([[2.0, 0.5], [0.5, 3.0]])
    G = contraction_matrices(A[None], field_exponents(2, 1), P[:, :, None], metric_exponents(2, 0),
                             RNG.normal(size=(3, 2)), 0.5)
    np.testing.assert_allclose(G[1, 0], A.T @ P + P @ A + 0.5 * P, atol=1e-14)


def test_sampled_eigenvalues_of_a_known_contraction():
    # f = -z, M = I: G = -2 I + gamma I, so every generalised eigenvalue is gamma - 2
    C1 = -np.eye(2)[None]
    W0 = np.eye(2)[:, :, None]
    max_g, min_m = sampled_eigenvalues(C1, field_exponents(2, 1), W0, metric_exponents(2, 0),
                                       sample_states(0, 100, 2), 0.5)
    assert np.isclose(max_g, -1.5, atol=1e-14) and np.isclose(min_m, 1.0)
    # an indefinite metric has no generalised eigenvalue: reported as inf
    max_g, min_m = sampled_eigenvalues(C1, field_exponents(2, 1), -W0, metric_exponents(2, 0),
                                       sample_states(0, 100, 2), 0.5)
    assert max_g == np.inf and min_m == -1.0


def test_sampled_eigenvalues_of_linear_fields_under_a_constant_metric_are_those_of_every_state():
    """G_k and M do not depend on z then: computed once, the numbers over all states, exactly."""
    rng = np.random.default_rng(5)
    n, K = 3, 4
    Cl = np.stack([-2 * np.eye(n) + 0.5 * rng.normal(size=(n, n)) for _ in range(K)])
    B = rng.normal(size=(n, n))
    P = (B @ B.T + n * np.eye(n))[:, :, None]
    fexps, mexps, Z = field_exponents(n, 1), metric_exponents(n, 0), sample_states(1, 400, n)
    max_g, min_m = sampled_eigenvalues(Cl, fexps, P, mexps, Z, 0.2)
    M = eval_metric(P, mexps, Z)
    assert max_g == generalized_max_eig(contraction_matrices(Cl, fexps, P, mexps, Z, 0.2), M).max()
    assert min_m == np.linalg.eigvalsh(M)[:, 0].min() > 0 and -10 < max_g < 10


def test_unit_metrics_and_field_jacobians_on_term_arrays_are_the_entrywise_matrices():
    vars = state_variables(2)
    units = unit_metrics(MEXPS, 2, vars)
    assert len(units) == 3 * MEXPS.shape[0]
    Z = np.random.default_rng(7).uniform(-1, 1, size=(7, 2))     # its own draws: any test order
    for (a, b, j), E in units:
        want = np.zeros((7, 2, 2))
        want[:, a, b] = want[:, b, a] = np.prod(Z ** MEXPS[j], axis=1)
        # the same monomial values up to the order of the products (1 ulp, measured 1.2e-16)
        np.testing.assert_allclose(E(Z, vars), want, rtol=1e-14, atol=0)
    for _, u in unit_fields(FEXPS, 2, vars):
        J, ref = field_jacobian(u, vars), jacobian(u, vars)
        assert all(J.entries[i, j] == ref.entries[i, j] for i in range(2) for j in range(2))


def test_sample_states_fill_twice_the_data_box_reproducibly():
    Z = sample_states(3, 1000, 2)
    assert Z.shape == (1000, 2) and np.abs(Z).max() <= 2.0 and np.abs(Z).max() > 1.9
    np.testing.assert_array_equal(Z, sample_states(3, 1000, 2))


def test_degrees_and_the_constant_monomial():
    assert degree(FEXPS) == 3 and degree(MEXPS) == 2
    assert MEXPS[constant_index(MEXPS)].sum() == 0
    assert contraction_degree(2, 3) == 4
    only_const = np.zeros_like(W)
    only_const[:, :, constant_index(MEXPS)] = np.eye(2)
    assert margin_degree(only_const, MEXPS, FEXPS) == 2           # a constant metric: deg f - 1
    assert margin_degree(W, MEXPS, FEXPS) == 4


def test_certificate_matrices_are_M_minus_eps_I_then_minus_G_k():
    mats = certificate_matrices(C, FEXPS, W, MEXPS, 0.3, 0.01)
    assert [name for name, _ in mats] == ["M - eps I", "-G[0]", "-G[1]"]
    Z = RNG.uniform(-1, 1, size=(5, 2))
    vars = state_variables(2)
    np.testing.assert_allclose(mats[0][1](Z, vars), numeric_metric(W, MEXPS, vars)(Z, vars) - 0.01 * np.eye(2),
                               atol=1e-12)
    np.testing.assert_allclose(mats[2][1](Z, vars), -contraction_matrices(C, FEXPS, W, MEXPS, Z, 0.3)[:, 1],
                               rtol=1e-10, atol=1e-10)


def _entrywise_G(f, M, vars, gamma):
    """The contraction operator by entry-by-entry Polynomial arithmetic (the reference)."""
    J = jacobian(f, vars)
    JtM = J.T @ M
    return JtM + JtM.T + M.directional_derivative(f, vars) + gamma * M


@pytest.mark.parametrize("n, fd, md", [(2, 3, 2), (3, 1, 2), (4, 1, 0)])
def test_vectorised_G_is_the_entrywise_G_for_decision_fields_and_decision_metrics(n, fd, md):
    rng = np.random.default_rng(n)
    vars, fexps, mexps = state_variables(n), field_exponents(n, fd), metric_exponents(n, md)
    Cn = rng.normal(size=(1, n, fexps.shape[0]))
    Wn = rng.normal(size=(n, n, mexps.shape[0]))
    Wn = Wn + Wn.transpose(1, 0, 2)
    f_dec = decision_fields(allocate(n * fexps.shape[0]).reshape(1, n, -1), fexps, vars)[0]
    M_dec = decision_metric({p: allocate(mexps.shape[0]) for p in symmetric_pairs(n)}, mexps, vars, n)
    f_num, M_num = numeric_fields(Cn, fexps, vars)[0], numeric_metric(Wn, mexps, vars)
    for f, M in ((f_dec, M_num), (f_num, M_dec), (f_num, M_num)):
        ref, got = _entrywise_G(f, M, vars, 0.7), contraction_polymatrix(f, M, vars, 0.7)
        for (i, j), p in np.ndenumerate(ref.entries):
            q = got.entries[i, j]
            assert np.array_equal(p.exps, q.exps) and np.array_equal(p.ids, q.ids)
            np.testing.assert_allclose(q.coef, p.coef, rtol=1e-13, atol=1e-13)

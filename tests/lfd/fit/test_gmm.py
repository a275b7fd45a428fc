"""EM on [z, zdot], BIC selection and the GMR cost ceiling."""
import numpy as np
from scipy.special import logsumexp

from sosdyn.lfd.fit.gmm import (
    MAX_BIC_COMPONENTS,
    PositionMixture,
    block_log_joint,
    fit_joint_gmm,
    gmm_linear_maps,
    gmr_cost,
    log_sum_exp,
)


def linear_samples(T=400):
    A = np.array([[-1.0, 4.0], [0.0, -1.0]])
    Z = np.random.default_rng(0).uniform(-1, 1, size=(T, 2))
    return Z, Z @ A.T, A


def test_one_gaussian_on_linear_data_is_the_linear_regression():
    Z, Zdot, A = linear_samples()
    gmm, bic = fit_joint_gmm(Z, Zdot, 1, seed=0)
    assert bic is None and gmm.n_components == 1
    A_hat, b_hat = gmm_linear_maps(gmm, 2)
    np.testing.assert_allclose(A_hat[0], A, atol=1e-4)
    np.testing.assert_allclose(b_hat[0], 0.0, atol=1e-4)
    assert gmr_cost(gmm, Z, Zdot) < 1e-8
    mix = PositionMixture.from_joint(gmm, 2)
    np.testing.assert_allclose(mix.responsibilities(Z), 1.0)


def test_bic_tries_one_to_ten_components_or_one_per_five_samples():
    Z, Zdot, _ = linear_samples(T=100)
    gmm, bic = fit_joint_gmm(Z, Zdot, "bic", seed=0)
    assert len(bic) == MAX_BIC_COMPONENTS == 10 and gmm.n_components == 1 + int(np.argmin(bic))
    _, bic = fit_joint_gmm(Z[:15], Zdot[:15], "bic", seed=0)
    assert len(bic) == 3


def test_log_sum_exp_is_scipys_to_the_bit_and_exact_on_known_rows():
    """log_sum_exp equals scipy.special.logsumexp bit for bit (ties at the maximum, -inf entries,
    spreads from 1e-3 to 800, K = 1..17), and log(e^0 + e^0) = log 2, log(e^5) = 5 exactly."""
    rng = np.random.default_rng(0)
    for K in (1, 2, 3, 8, 17):
        A = rng.normal(size=(2000, K)) * rng.choice([1e-3, 1.0, 30.0, 800.0], size=(2000, 1))
        A[::7, 0] = A[::7, -1]
        A[::13] = np.round(A[::13])
        if K > 1:
            A[::11, 1] = -np.inf
        assert np.array_equal(log_sum_exp(A), logsumexp(A, axis=1, keepdims=True))
    assert log_sum_exp(np.array([[0.0, 0.0], [5.0, -np.inf]]))[:, 0].tolist() == [np.log(2.0), 5.0]


def test_block_log_joint_is_each_mixtures_own_to_the_bit():
    """block_log_joint: three mixtures (n = 2 and n = 7, K = 4) on three blocks of rows in one pass
    give each block its own mixture's log_joint bit for bit; a standard normal at its mean gives
    log w - n/2 log(2 pi)."""
    rng = np.random.default_rng(3)
    for n in (2, 7):
        mixes = []
        for _ in range(3):
            A = rng.normal(size=(4, n, n))
            mixes.append(PositionMixture(rng.dirichlet(np.ones(4)), rng.normal(size=(4, n)),
                                         A @ A.transpose(0, 2, 1) + 0.1 * np.eye(n)))
        X = rng.normal(size=(15, n))
        blocks = [X[5 * b:5 * (b + 1)] for b in range(3)]
        together = block_log_joint(mixes, 5)(X)
        assert np.array_equal(together, np.vstack([m.log_joint(B) for m, B in zip(mixes, blocks)]))
    unit = PositionMixture(np.array([0.25, 0.75]), np.zeros((2, 3)), np.broadcast_to(np.eye(3), (2, 3, 3)).copy())
    np.testing.assert_allclose(block_log_joint([unit, unit], 1)(np.zeros((2, 3))),
                               np.log([[0.25, 0.75]] * 2) - 1.5 * np.log(2 * np.pi), rtol=1e-15)


def test_block_log_joint_tempers_each_block_with_its_own_bound():
    """Gating bounds None, 2 and 5 on three blocks (gating="tempered" candidates, or one without):
    each block's numbers are its own mixture's tempered log_joint, bit for bit, and rows beyond a
    bound differ from the plain posterior's."""
    rng = np.random.default_rng(4)
    mixes = []
    for bound in (None, 2.0, 5.0):
        A = rng.normal(size=(4, 2, 2))
        mixes.append(PositionMixture(rng.dirichlet(np.ones(4)), rng.normal(size=(4, 2)),
                                     A @ A.transpose(0, 2, 1) + 0.1 * np.eye(2), bound))
    X = 3 * rng.normal(size=(30, 2))
    together = block_log_joint(mixes, 10)(X)
    each = np.vstack([m.log_joint(X[10 * b:10 * (b + 1)]) for b, m in enumerate(mixes)])
    assert np.array_equal(together, each)
    plain = PositionMixture(mixes[2].weights, mixes[2].means, mixes[2].covariances)
    assert np.abs(plain.log_joint(X[20:]) - together[20:]).max() > 1.0

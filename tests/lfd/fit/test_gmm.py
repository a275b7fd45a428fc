"""EM on [z, zdot], BIC selection and the GMR cost ceiling."""
import numpy as np

from sosdyn.lfd.fit.gmm import MAX_BIC_COMPONENTS, PositionMixture, fit_joint_gmm, gmm_linear_maps, gmr_cost


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

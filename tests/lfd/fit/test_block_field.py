"""block_field: the warp choice's scoring field, every candidate's rows in one evaluation."""
import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.lfd.fit.contraction import field_exponents
from sosdyn.lfd.fit.gmm import PositionMixture
from sosdyn.lfd.fit.pipeline import Fit, block_field, field_at
from sosdyn.lfd.fit.warp import LIP_FACTOR


def random_fit(rng, n=2, K=3, m=None, bumps=5):
    """A Fit with a random mixture, linear fields, a goal, a scale and (bumps > 0) a warp in z-units."""
    A = rng.normal(size=(K, n, n))
    mix = PositionMixture(rng.dirichlet(np.ones(K)), rng.normal(size=(K, n)), A @ A.transpose(0, 2, 1) + 0.2 * np.eye(n))
    warp = None
    if bumps:
        S = rng.uniform(0.3, 1.0, bumps)
        V = rng.normal(size=(bumps, n))
        V *= (0.6 * S / (LIP_FACTOR * np.linalg.norm(V, axis=1)))[:, None]
        warp = {"centers": rng.normal(size=(bumps, n)), "vectors": V, "sigmas": S}
    return Fit(goal_=rng.normal(size=n), scale_=float(rng.uniform(0.5, 3)), warp_=warp, mixture_=mix,
               C_=rng.normal(size=(K, n, n)), field_exps_=field_exponents(n, 1))


@pytest.mark.parametrize("n", [2, 7])
def test_block_field_is_each_fits_own_field_to_the_bit(n):
    """Three fits (a warp of 5 bumps, none, a warp of 3) on blocks of 4 rows: block_field gives, bit
    for bit, each fit's field_at on its block, with all three live and with the middle one stopped."""
    rng = np.random.default_rng(n)
    fits = [random_fit(rng, n, bumps=5), random_fit(rng, n, bumps=0), random_fit(rng, n, bumps=3)]
    field = block_field(fits)
    X = rng.normal(size=(12, n))
    own = lambda b, Xb: field_at(Xb, fits[b].goal_, fits[b].scale_, fits[b].mixture_, fits[b].C_,  # noqa: E731
                                 fits[b].field_exps_, fits[b].warp_)
    for _ in range(2):                      # the prepared evaluation is reused from call to call
        assert np.array_equal(field(X, [0, 1, 2]), np.vstack([own(b, X[4 * b:4 * b + 4]) for b in range(3)]))
        assert np.array_equal(field(X[:8], [0, 2]), np.vstack([own(0, X[:4]), own(2, X[4:8])]))
        X = X + 0.1


def test_block_field_with_other_K_and_a_non_finite_state():
    """Fits of different K fall back to block-by-block evaluation (the same numbers); a NaN state is
    an InputError naming it, not a NaN velocity."""
    rng = np.random.default_rng(1)
    fits = [random_fit(rng, K=2), random_fit(rng, K=4)]
    X = rng.normal(size=(6, 2))
    want = np.vstack([field_at(X[3 * b:3 * b + 3], f.goal_, f.scale_, f.mixture_, f.C_, f.field_exps_, f.warp_)
                      for b, f in enumerate(fits)])
    assert np.array_equal(block_field(fits)(X, [0, 1]), want)
    X[4, 1] = np.nan
    with pytest.raises(InputError, match="not finite"):
        block_field(fits[:1] * 2)(X, [0, 1])

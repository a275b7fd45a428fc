"""The one-state evaluator (sosdyn.lfd.runtime.predictor) computes what CDSP.predict computes (its speed
against predict is a benchmark target: problems.bench.predict, `make bench`)."""
import numpy as np
import pytest

from sosdyn.errors import InputError, NotFittedError
from sosdyn.lfd.model.cdsp import CDSP


@pytest.fixture
def model(field_model):
    """The conftest's linear / cubic / warped models (fitted once per session)."""
    return field_model


def test_same_numbers_as_predict_in_twice_the_data_box(model):
    rng = np.random.default_rng(1)
    X = model.goal_ + model.scale_ * rng.uniform(-2, 2, size=(2000, model.dim_))
    V = model.predict(X)
    fast = model.predictor()
    F = np.array([fast(x) for x in X])
    rel = np.abs(F - V).max(axis=1) / np.abs(V).max(axis=1)
    assert rel.max() < 1e-12
    assert F.shape == (2000, 2) and fast(X[0]).shape == (2,)


def test_far_states_use_the_nearest_component_like_predict(linear_demos):
    model = CDSP(n_components=3, warp="none").fit(linear_demos)
    fast = model.predictor()
    for x in ([1e160, -3e159], [-2e158, 5e157], [4e3, 1e160]):   # every l_k underflows: one-hot h
        x = np.array(x)
        np.testing.assert_allclose(fast(x), model.predict(x)[0], rtol=1e-12)


def test_wrong_states_are_refused_with_the_reason(model):
    fast = model.predictor()
    with pytest.raises(InputError, match=r"shape \(2,\)"):
        fast(np.zeros(3))
    with pytest.raises(InputError, match="finite"):
        fast([np.nan, 0.0])
    if model.field_degree == 3:                 # z^3 overflows: refused like predict refuses it
        with pytest.raises(InputError, match="overflows float"):
            fast([1e120, 1e120])
        with pytest.raises(InputError, match="overflows float"):
            model.predict([1e120, 1e120])


def test_unfitted_model_has_no_predictor():
    with pytest.raises(NotFittedError):
        CDSP().predictor()


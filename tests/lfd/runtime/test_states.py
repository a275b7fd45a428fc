"""Every public entry point that takes states refuses text, ragged lists, dicts, booleans and
complex numbers with an InputError and a hint (never numpy's ValueError / TypeError)."""
import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.lfd.runtime.states import as_states, limit_speed

BAD = [
    (["a", "b"], "text|not numbers"),
    ("1,2", r"text '1,2'.*parse the text"),
    ([[1.0, 2.0], [3.0]], "not a rectangular array"),
    ({"x": 1.0, "y": 2.0}, r"is a dict.*d\['x'\]"),
    ([1 + 2j, 3.0], "complex"),
    (np.array([1.0 + 0j, 2.0]), "complex"),
    ([True, False], "booleans"),
    (None, "not a rectangular array"),
    ([1.0, None], "not a rectangular array"),
]


@pytest.mark.parametrize("value, message", BAD)
def test_as_states_refuses_with_a_hint(value, message):
    with pytest.raises(InputError, match=message) as info:
        as_states(value, 2)
    assert "Try:" in str(info.value)


@pytest.mark.parametrize("value, message", BAD)
def test_every_entry_point_refuses_with_a_hint(field_model, value, message):
    model = field_model
    step = model.predictor()
    calls = [lambda: model.predict(value), lambda: model.rollout(value, 1.0), lambda: step(value)]
    if value is not None:                                           # goal=None: the model's goal
        calls += [lambda: model.rollout(model.goal_, 1.0, goal=value), lambda: step(model.goal_, goal=value)]
    for call in calls:
        with pytest.raises(InputError, match=message):
            call()


def test_integers_and_lists_are_still_states(field_model):
    model = field_model
    x = [int(v) for v in np.round(model.goal_ + model.scale_)]
    np.testing.assert_allclose(model.predictor()(x), model.predict(np.array(x, float))[0], rtol=1e-12)
    with pytest.raises(InputError, match=r"one state of shape \(2,\)"):
        model.predictor()([x, x])


def test_limit_speed_scales_only_fast_rows():
    V = np.array([[3.0, 4.0], [0.3, 0.4], [0.0, 0.0]])
    np.testing.assert_allclose(limit_speed(V, 1.0), [[0.6, 0.8], [0.3, 0.4], [0.0, 0.0]])
    assert limit_speed(V, None) is V

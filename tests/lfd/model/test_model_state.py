"""The state of a model file, field by field, without the estimator."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.fit.contraction import field_exponents, metric_exponents
from sosdyn.lfd.fit.gmm import PositionMixture
from sosdyn.lfd.model.fileformat import plain
from sosdyn.lfd.model.content import STATE_FIELDS, check_param_names, state_record, validate_state


def good_state(K=1, n=2):
    cons = [{"name": "c", "vars": ["z1", "z2"], "basis": [[1, 0], [0, 1]], "gram": [[1.0, 0.0], [0.0, 1.0]]}]
    state = {"dim_": n, "goal_": np.zeros(n), "scale_": 2.0, "dt_": 0.01, "units_": "mm", "n_components_": K,
             "gmr_cost_": 0.5, "C_": -np.ones((K, n, n)), "W_": np.eye(n)[:, :, None],
             "field_exps_": field_exponents(n, 1), "metric_exps_": metric_exponents(n, 0),
             "mixture_": PositionMixture(np.ones(K) / K, np.zeros((K, n)), np.stack([np.eye(n)] * K)),
             "certificate_": {"status": "optimal", "eps": 5e-4, "constraints": cons * (K + 1)},
             "history_": [{"step": "x"}], "metric_collapse_": None, "timings_": {}}
    return plain(state_record(state))


def test_a_valid_state_round_trips_to_arrays():
    out = validate_state(good_state(), 1, 1, 0, 5e-4)
    assert set(out) == set(STATE_FIELDS)
    np.testing.assert_array_equal(out["C_"], -np.ones((1, 2, 2)))
    assert isinstance(out["mixture_"], PositionMixture) and out["field_exps_"].dtype == np.int64


@pytest.mark.parametrize("edit, match", [
    (lambda s: s.update(n_components_=2), r"state.n_components_ = 2 but params.n_components = 1"),
    (lambda s: s.update(W_=[[[1.0], [2.0]], [[0.0], [1.0]]]), "W_ is not symmetric"),
    (lambda s: s["certificate_"].update(eps=1e-3), r"eps / 2 = 0.0005"),
    (lambda s: s.update(extra=1), r"unknown field state\.extra"),
    (lambda s: s.pop("timings_"), "the field state.timings_ is missing"),
])
def test_a_bad_field_is_named(edit, match):
    state = good_state()
    edit(state)
    with pytest.raises(sd.ModelFileError, match=match):
        validate_state(state, 1, 1, 0, 5e-4)


def test_param_names_must_match_exactly():
    check_param_names({"a": 1, "b": 2}, ("a", "b"))
    with pytest.raises(sd.ModelFileError, match=r"params lacks \['b'\] and has unknown \['c'\]"):
        check_param_names({"a": 1, "c": 2}, ("a", "b"))

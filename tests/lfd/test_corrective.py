"""sosdyn.lfd.corrective: corrective pairs, rollout deviation, CorrectiveCDSP (rounds chosen on training data)."""
import numpy as np
import pytest

from sosdyn.errors import InputError, NotFittedError
from sosdyn.lfd import lasa
from sosdyn.lfd.corrective import (
    CorrectiveCDSP,
    corrective_pairs,
    nearest,
    rollout_deviation,
)
from sosdyn.lfd.data import Demonstrations

SMALL = {"n_components": 2, "max_iter": 4, "verify_samples": 500}


def test_nearest_indices_and_distances():
    P = np.array([[0.0, 0.0], [3.0, 0.0]])
    j, d = nearest(P, np.array([[1.0, 0.0], [2.0, 4.0]]))
    assert j.tolist() == [0, 1]
    assert d == pytest.approx([1.0, np.hypot(1.0, 4.0)])


def test_corrective_label_is_demo_velocity_plus_pull_back():
    P, V = np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[1.0, 0.0], [2.0, 0.0]])
    states = np.array([[0.0, 0.5], [1.0, 0.001], [1.2, -0.3]])
    X, Xdot = corrective_pairs(states, P, V, tau=0.5, min_dist=0.01)
    assert X.tolist() == [[0.0, 0.5], [1.2, -0.3]]            # the state 0.001 from the demo is dropped
    assert Xdot == pytest.approx(np.array([[1.0, -1.0], [2.0 - 0.4, 0.6]]))


def test_rollout_deviation_is_the_symmetric_mean_nearest_distance():
    demo = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert rollout_deviation(demo + [0.0, 1.0], demo) == pytest.approx(1.0)
    # a rollout that stops at the demo's start: 0 one way, (0 + 2) / 2 the other
    assert rollout_deviation(np.array([[0.0, 0.0]]), np.array([[0.0, 0.0], [2.0, 0.0]])) == pytest.approx(0.5)


@pytest.mark.parametrize("kwargs", [{"rounds": -1}, {"rounds": 1.5}, {"tau": 0}, {"tau": np.inf},
                                    {"min_dist": -0.1}, {"max_extra": 3}, {"start_index": True}])
def test_bad_parameters_are_input_errors(kwargs, linear_demos):
    with pytest.raises(InputError, match="Try"):
        CorrectiveCDSP(SMALL, **kwargs).fit(linear_demos)


def test_predict_before_fit():
    with pytest.raises(NotFittedError, match="fit"):
        CorrectiveCDSP().predict(np.zeros((1, 2)))


def test_start_index_beyond_the_demo(linear_demos):
    with pytest.raises(InputError, match="start_index"):
        CorrectiveCDSP(SMALL, rounds=0, start_index=200).fit(linear_demos)


def test_leaf2_rounds_lower_the_training_deviation(leaf):     # ``leaf``: skipped without LASA data
    """LASA Leaf_2 (demos 1-4, every 2nd sample): the corrective round reproduces the training
    demos more closely than the plain CDSP() fit, and the estimator keeps the best round (certified)."""
    demos = lasa.load_lasa("Leaf_2")
    train = Demonstrations(list(demos)[:4], demos.name, demos.units).subsample(2)
    model = CorrectiveCDSP({}, rounds=1, tau=0.5, start_index=19).fit(train)
    assert len(model.scores_) == 2 and model.n_extra_[0] > 100
    assert model.round_ == int(np.argmin(model.scores_))
    assert min(model.scores_) < model.scores_[0] * 0.9          # measured: 5.52 -> 2.98 mm
    assert model.certified_ and model.model_.verify().passed
    X = train[0].pos[::50]
    assert np.array_equal(model.predict(X), model.model_.predict(X))

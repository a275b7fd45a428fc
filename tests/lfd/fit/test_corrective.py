"""Corrective refits (sosdyn.lfd.fit.corrective, CDSP's corrective_rounds): pairs, rest rule, scores, rounds."""
import dataclasses

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InputError
from sosdyn.lfd.fit import pipeline
from sosdyn.lfd.fit.certificate import check_certificate
from sosdyn.lfd.fit.corrective import (
    REST_FRACTION,
    ROLLOUT_SPAN,
    augmented,
    corrective_demonstration,
    corrective_pairs,
    demo_score,
    demo_scores,
    nearest,
    rest_rule,
    rollout_deviation,
    rollout_starts,
    thin,
    training_rollouts,
    training_score,
)
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.lasa import load_lasa


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


def test_thin_keeps_evenly_spaced_rows_with_both_ends():
    X = np.arange(10.0)[:, None]
    kept, kept_dot = thin(X, -X, 4)
    assert kept.ravel().tolist() == [0.0, 3.0, 6.0, 9.0] and kept_dot.ravel().tolist() == [0.0, -3.0, -6.0, -9.0]
    assert thin(X, -X, 10)[0] is X


def test_rollout_deviation_is_the_symmetric_mean_nearest_distance():
    demo = np.array([[0.0, 0.0], [1.0, 0.0]])
    assert rollout_deviation(demo + [0.0, 1.0], demo) == pytest.approx(1.0)
    # a rollout that stops at the demo's start: 0 one way, (0 + 2) / 2 the other
    assert rollout_deviation(np.array([[0.0, 0.0]]), np.array([[0.0, 0.0], [2.0, 0.0]])) == pytest.approx(0.5)


def test_starts_are_the_first_samples_then_pairwise_midpoints(make_line_demo):
    demos = Demonstrations([make_line_demo((4, 0)), make_line_demo((0, 4)), make_line_demo((-4, 2))])
    S = rollout_starts(demos)
    assert S.tolist() == [[4, 0], [0, 4], [-4, 2], [2, 2], [0, 1], [-2, 3]]


def test_rest_rule_is_relative_to_the_data(make_line_demo):
    """dt = the sample step, vel_tol = REST_FRACTION x max |velocity component|, at most
    ROLLOUT_SPAN x the duration; the same in metres and millimetres (tolerance x 1000)."""
    demos = Demonstrations([make_line_demo((4, 0), T=51, duration=2.0), make_line_demo((0, 2), T=51, duration=2.0)])
    dt, tol, steps = rest_rule(demos)
    assert dt == pytest.approx(0.04) and steps == round(ROLLOUT_SPAN * 2.0 / 0.04)
    assert tol == pytest.approx(REST_FRACTION * 4 * 1.5 / 2.0)        # peak of the cubic time law: 1.5 |d| / T
    mm = Demonstrations([Demonstration(d.t, 1000 * d.pos, 1000 * d.vel) for d in demos])
    assert rest_rule(mm) == pytest.approx((dt, 1000 * tol, steps))
    with sd.limits(max_rollout_steps=300):                             # 3 starts share the step budget
        assert rest_rule(demos)[2] == 100


def test_training_rollouts_of_the_exact_field_follow_the_demos(linear_demos, linear_system):
    A, goal = linear_system
    reps = training_rollouts(lambda X: (X - goal) @ A.T, linear_demos)
    assert len(reps) == 4 + 6
    assert np.linalg.norm(reps[0][-1] - goal) < 0.05                  # came to rest at the goal
    assert training_score(reps, linear_demos) == pytest.approx(0.029, abs=0.002)   # Euler's error, dt 0.03 s
    assert training_rollouts(lambda X: X * 1e300, linear_demos) is None   # overflows: no rollouts
    assert training_rollouts(lambda X: X - goal, linear_demos) is None   # finite (1.03^1000), but far off
    assert training_score(None, linear_demos) == np.inf


def test_the_pseudo_demonstration_ends_at_the_goal(linear_demos):
    X, Xdot = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[0.5, 0.5], [1.0, 1.0]])
    d = corrective_demonstration(X, Xdot, np.array([2.0, -1.0]), 0.1, "round 1")
    assert d.t.tolist() == pytest.approx([0.0, 0.1, 0.2])
    assert d.pos[-1].tolist() == [2.0, -1.0] and d.vel[-1].tolist() == [0.0, 0.0]
    both = augmented(linear_demos, [d])
    assert len(both) == 5 and both.name == "linear" and both.units == "m"


@pytest.mark.parametrize("kwargs, match", [
    ({"corrective_rounds": -1}, "corrective_rounds must be an integer >= 0"),
    ({"corrective_rounds": 1.5}, "corrective_rounds must be an integer"),
    ({"corrective_rounds": True}, "corrective_rounds must be an integer"),
    ({"corrective_rounds": 11}, "corrective_rounds must be at most 10"),
    ({"corrective_tau": 0}, "corrective_tau must be a positive finite number"),
    ({"corrective_tau": np.inf}, "corrective_tau must be a positive finite number"),
    ({"corrective_min_dist": -0.1}, "corrective_min_dist must be a finite number >= 0"),
    ({"corrective_min_dist": np.nan}, "corrective_min_dist must be a finite number >= 0"),
])
def test_bad_corrective_parameters_fail_before_any_optimisation(kwargs, match, linear_demos, monkeypatch):
    monkeypatch.setattr(pipeline, "fit_joint_gmm", lambda *a: pytest.fail("EM ran before the check"))
    with pytest.raises(InputError, match=match) as info:
        sd.CDSP(**kwargs).fit(linear_demos)
    assert "Try: the default" in str(info.value)


def test_rounds_are_tagged_and_a_worse_refit_keeps_the_plain_fit(linear_demos):
    """Exact linear demos: round 0 reproduces them up to Euler's error (0.029 m); the refit on the
    pairs from the midpoint starts is farther off (0.256 m), so round 0 is kept, and it is the
    corrective_rounds=0 model."""
    rows = []
    small = {"n_components": 1, "gamma": 0.5, "max_iter": 5, "verify_samples": 500}
    model = sd.CDSP(**small, corrective_rounds=1, warp="none", progress=rows.append).fit(linear_demos)
    plain = sd.CDSP(**small, warp="none").fit(linear_demos)
    assert model.corrective_scores_ == pytest.approx([0.029, 0.256], abs=0.005)
    assert model.corrective_round_ == 0 and model.corrective_pairs_ == [284] and plain.corrective_scores_ == []
    np.testing.assert_array_equal(model.C_, plain.C_)
    assert [r["round"] for r in rows[:len(plain.history_)]] == [0] * len(plain.history_)
    assert {r["round"] for r in rows} == {0, 1} and model.history_ == rows


def test_an_uncertified_refit_ends_the_rounds_and_keeps_a_certified_one(linear_demos, monkeypatch):
    """The second fit's check is made to fail: NotCertifiedError is not raised, round 0 is kept."""
    calls = []

    def failing_second(*args):
        report = check_certificate(*args)
        calls.append(report)
        return dataclasses.replace(report, passed=len(calls) != 2)

    monkeypatch.setattr(pipeline, "check_certificate", failing_second)
    model = sd.CDSP(n_components=1, gamma=0.5, max_iter=5, verify_samples=500, corrective_rounds=3,
                warp="none").fit(linear_demos)
    assert len(calls) == 2 and model.corrective_round_ == 0 and len(model.corrective_scores_) == 1
    assert model.certified_ and {r["round"] for r in model.history_} == {0}
    monkeypatch.setattr(pipeline, "check_certificate", lambda *a: dataclasses.replace(check_certificate(*a),
                                                                                            passed=False))
    with pytest.raises(sd.NotCertifiedError):              # round 0 itself: raised as for a plain fit
        sd.CDSP(n_components=1, gamma=0.5, max_iter=5, verify_samples=500, corrective_rounds=3,
                warp="none").fit(linear_demos)


@pytest.fixture(scope="module")
def leaf2_train(leaf):                    # ``leaf``: skipped without the LASA data
    """LASA Leaf_2, demonstrations 1-4, every 2nd sample (the ds-opt protocol's training set)."""
    demos = load_lasa("Leaf_2")
    return Demonstrations(list(demos)[:4], demos.name, demos.units).subsample(2)


@pytest.fixture(scope="module")
def leaf2_models(leaf2_train):
    return sd.CDSP(warp="none").fit(leaf2_train), sd.CDSP(corrective_rounds=3, warp="none").fit(leaf2_train)


def test_corrective_rounds_lower_the_training_deviation_on_leaf2(leaf2_train, leaf2_models):
    """Measured (random_state 0): round scores 6.53 -> 3.18 -> 2.83 -> 3.45 mm, round 2 kept; every
    round certified (an uncertified refit ends the rounds, see above)."""
    plain, model = leaf2_models
    plain_score = training_score(training_rollouts(lambda X: plain.field(X, plain.goal_), leaf2_train), leaf2_train)
    assert model.corrective_scores_[0] == pytest.approx(plain_score, rel=1e-9)   # round 0 = the plain fit
    assert len(model.corrective_scores_) == 4 and min(model.corrective_pairs_) > 100
    assert model.corrective_round_ == int(np.argmin(model.corrective_scores_)) > 0
    assert min(model.corrective_scores_) < 0.6 * plain_score
    assert plain_score == pytest.approx(6.53, abs=0.15)
    assert model.certified_ and model.verify().passed
    assert {r["round"] for r in model.history_} == {0, 1, 2, 3}


def test_a_corrective_model_round_trips_through_a_file(leaf2_models, tmp_path):
    model = leaf2_models[1]
    loaded = sd.load_model(model.save(tmp_path / "m.json"))
    assert (loaded.corrective_rounds, loaded.corrective_tau, loaded.corrective_min_dist) == (3, 0.5, 0.02)
    X = np.array([[-10.0, 5.0], [3.0, -20.0]])
    np.testing.assert_array_equal(loaded.predict(X), model.predict(X))
    assert loaded.certified_ and loaded.dt_ == model.dt_ and loaded.scale_ == model.scale_


def test_demo_scores_of_several_fields_are_each_ones_demo_score(linear_demos, linear_system):
    """Three fields scored in one Euler loop: the true system (score near 0: Euler's error only), a
    slower one, and one that diverges (inf); each equal, bit for bit, to its own demo_score."""
    A, goal = linear_system
    fields = [lambda X: (X - goal) @ A.T, lambda X: 0.5 * (X - goal) @ A.T, lambda X: -(X - goal) @ A.T]
    m = len(linear_demos)
    both = demo_scores(lambda X, live: np.vstack([fields[b](X[k * m:(k + 1) * m]) for k, b in enumerate(live)]),
                       3, linear_demos)
    assert both == [demo_score(f, linear_demos) for f in fields]
    assert both[0] < 0.05 < both[1] < np.inf == both[2]

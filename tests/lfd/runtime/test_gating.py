"""The mixture weights tempered off the data (issue 22 item 10, issue 34 item 2; sosdyn.lfd.fit.gmm): the
plain posterior, bit for bit, where min_k d_k^2 <= c; beyond, a softmax of c d_k^2 / d_min^2 (tempered) or
beyond tau = F the tempered log-likelihood less log pi divided by tau / F, fading to pi (smooth, the default)."""
import json

import numpy as np
import pytest
from scipy.stats import chi2

from sosdyn.errors import ModelFileError
from sosdyn.lfd.fit.gmm import FADE, PositionMixture, gate_bound, with_bound
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.fileformat import _digest
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.runtime.export_python import to_python

from export_support import import_source


def two(bound, wide=4.0, fade=None, weights=(0.5, 0.5)):
    """pi = weights, mu = (-1, 0) and (1, 0), S = I and wide * I."""
    return PositionMixture(np.array(weights), np.array([[-1.0, 0.0], [1.0, 0.0]]),
                           np.array([np.eye(2), wide * np.eye(2)]), bound, fade)


def test_off_the_data_the_known_tempered_weights():
    """At x = (2, 4) with S = I for both: q = (25, 17), tau = 17 / 4, l_1 - l_2 = -(25 - 17) / (2 tau)
    = -16/17, h_1 = 1 / (1 + e^(16/17)); the plain posterior: 1 / (1 + e^4)."""
    x = np.array([[2.0, 4.0]])
    assert two(4.0, 1.0).responsibilities(x)[0, 0] == pytest.approx(1 / (1 + np.exp(16 / 17)), rel=1e-14)
    assert two(None, 1.0).responsibilities(x)[0, 0] == pytest.approx(1 / (1 + np.exp(4.0)), rel=1e-14)


def test_off_the_data_the_known_faded_weights():
    """At x = (2, 4), S = I, pi = (0.2, 0.8), bound 4: q = (25, 17), tau = 17 / 4; the tempered terms less
    log pi (equal normalisers less log pi) differ by -(25 - 17) / (2 tau) = -16/17; with fade 2 they are divided
    by tau / 2 = 17 / 8: l_1 - l_2 = log(0.2 / 0.8) - (16/17) (8/17). With fade 5 >= tau: the tempered weights."""
    x = np.array([[2.0, 4.0]])
    h = two(4.0, 1.0, fade=2.0, weights=(0.2, 0.8)).responsibilities(x)[0, 0]
    assert h == pytest.approx(1 / (1 + 4.0 * np.exp(16 / 17 * 8 / 17)), rel=1e-14)
    h = two(4.0, 1.0, fade=5.0, weights=(0.2, 0.8)).responsibilities(x)[0, 0]
    assert h == pytest.approx(1 / (1 + 4.0 * np.exp(16 / 17)), rel=1e-14)


@pytest.mark.parametrize("fade", [None, 3.0])
def test_inside_the_bound_the_plain_posterior_bit_for_bit(fade):
    rng = np.random.default_rng(0)
    X = rng.uniform(-6, 6, (4000, 2))
    tempered, plain = two(9.0, fade=fade).responsibilities(X), two(None).responsibilities(X)
    inv, _ = two(9.0).factors()
    q = (np.einsum("kij,mkj->mki", inv, X[:, None] - two(9.0).means[None]) ** 2).sum(-1).min(axis=1)
    assert 0.1 < (q <= 9.0).mean() < 0.9
    assert np.array_equal(tempered[q <= 9.0], plain[q <= 9.0])
    assert np.abs(tempered[q > 9.0] - plain[q > 9.0]).max() > 0.01


def test_within_the_fade_the_tempered_weights_bit_for_bit():
    rng = np.random.default_rng(1)
    X = rng.uniform(-12, 12, (4000, 2))
    faded, tempered = two(2.0, fade=3.0).responsibilities(X), two(2.0).responsibilities(X)
    inv, _ = two(2.0).factors()
    tau = (np.einsum("kij,mkj->mki", inv, X[:, None] - two(2.0).means[None]) ** 2).sum(-1).min(axis=1) / 2.0
    assert 0.1 < (tau <= 3.0).mean() < 0.9
    assert np.array_equal(faded[tau <= 3.0], tempered[tau <= 3.0])
    assert np.abs(faded[tau > 3.0] - tempered[tau > 3.0]).max() > 0.01


def test_the_far_branch_is_the_limit_of_the_regular_one():
    """Along x = t (3, 4): q_1 / q_2 -> 4 (S_2 = 4 I), so h_1 -> 1 / (1 + exp(1.5 c - 2 log 2)) (the
    normalisers differ by log det L_2 = log 4); t = 1e100 takes the regular path, t = 1e200 (the forms
    overflow) the far one."""
    limit = 1 / (1 + np.exp(1.5 * 4.0 - 2 * np.log(2)))
    mix = two(4.0)
    for t in (1e100, 1e200):
        assert mix.responsibilities(np.array([[3.0, 4.0]]) * t)[0, 0] == pytest.approx(limit, rel=1e-12)
    assert two(None).responsibilities(np.array([[3e200, 4e200]]))[0].tolist() == [0.0, 1.0]   # one-hot


def test_far_off_the_smooth_weights_fade_to_pi():
    """Along x = t (3, 4): tempered, the weights keep a direction-dependent limit (above); smooth, they tend
    to pi = (0.2, 0.8), at t = 1e100 (regular path) and t = 1e200 (the forms overflow: the far path)."""
    mix = two(4.0, fade=3.0, weights=(0.2, 0.8))
    for t in (1e100, 1e200):
        assert mix.responsibilities(np.array([[3.0, 4.0]]) * t)[0] == pytest.approx([0.2, 0.8], rel=1e-12)


def test_thin_gaussians_turn_smoothly_off_the_data():
    """Two thin Gaussians (sd 0.01): crossing the face between them 5 units away, the plain weights
    jump from 0 to 1 within a step of 1e-3; the tempered ones move by at most 2 % a step, the smooth ones
    (faded to pi there) by less than 1e-4."""
    mix = PositionMixture(np.array([0.5, 0.5]), np.array([[-1.0, 0.0], [1.0, 0.0]]), np.array([1e-4 * np.eye(2)] * 2))
    X = np.column_stack([np.linspace(-0.5, 0.5, 1000), np.full(1000, 5.0)])
    jump = lambda m: np.abs(np.diff(m.responsibilities(X)[:, 0])).max()      # noqa: E731
    assert jump(mix) > 0.99
    assert jump(with_bound(mix, chi2.ppf(0.999, 2))) < 0.02
    assert jump(with_bound(mix, chi2.ppf(0.999, 2), fade=3.0)) < 1e-4


@pytest.fixture(scope="module", params=["tempered", "smooth"])
def fitted(linear_demos, request):
    return CDSP(n_components=3, warp="none", gating=request.param).fit(linear_demos)


def test_the_default_gating_is_smooth_and_the_fit_is_the_same(fitted, linear_demos):
    """gating="tempered" or "smooth" (the default) changes the weights only: the same coefficients, bit for bit."""
    plain = CDSP(n_components=3, warp="none", gating="posterior").fit(linear_demos)
    assert CDSP().gating == "smooth"
    assert plain.mixture_.bound is None and fitted.mixture_.bound > 0
    assert fitted.mixture_.fade == (FADE if fitted.gating == "smooth" else None)
    assert np.array_equal(plain.C_, fitted.C_) and np.array_equal(plain.mixture_.covariances, fitted.mixture_.covariances)


def test_a_fit_keeps_the_plain_posterior_at_every_training_point(fitted, linear_demos):
    model = fitted
    Z = (np.vstack([d.pos for d in linear_demos]) - model.goal_) / model.scale_
    assert model.mixture_.bound == gate_bound(model.mixture_, Z) >= chi2.ppf(0.999, 2)
    assert np.array_equal(model.mixture_.responsibilities(Z), with_bound(model.mixture_, None).responsibilities(Z))


def test_predictor_and_python_export_temper_like_the_model(fitted, tmp_path):
    model = fitted
    X = model.goal_ + model.scale_ * np.random.default_rng(2).uniform(-3, 3, (300, 2))
    inv, _ = model.mixture_.factors()
    Z = (X - model.goal_) / model.scale_
    q = (np.einsum("kij,mkj->mki", inv, Z[:, None] - model.mixture_.means[None]) ** 2).sum(-1).min(axis=1)
    X = X[q > 2 * model.mixture_.bound]                             # off the data only: tau >= 2
    assert len(X) > 50
    V, fast, gen = model.predict(X), model.predictor(), import_source(to_python(model), tmp_path / "g.py")
    for W in (np.array([fast(x) for x in X]), gen.predict(X), np.array([gen.predict(x) for x in X])):
        assert (np.abs(W - V).max(axis=1) / np.abs(V).max(axis=1)).max() < 1e-12
    plain = with_bound(model.mixture_, None)
    assert np.abs(plain.responsibilities(Z[q > 2 * model.mixture_.bound]) -
                  model.mixture_.responsibilities(Z[q > 2 * model.mixture_.bound])).max() > 0.01


@pytest.fixture(scope="module")
def saved(fitted, tmp_path_factory):
    path = tmp_path_factory.mktemp("gating") / "m.json"
    fitted.save(path)
    return json.loads(path.read_text())


def _write(data, path):
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    path.write_text(json.dumps(data))
    return path


def test_a_file_without_the_fade_loads_with_the_tempered_forms(saved, tmp_path):
    data = json.loads(json.dumps(saved))
    fade = data["state"]["mixture_"].pop("fade")                   # a file older than the smooth gating
    old, new = load_model(_write(data, tmp_path / "old.json")), load_model(_write(saved, tmp_path / "new.json"))
    assert old.mixture_.fade is None and new.mixture_.fade == fade and old.mixture_.bound == new.mixture_.bound
    if fade is not None:
        X = new.goal_ + new.scale_ * np.random.default_rng(0).uniform(-30, 30, (500, 2))
        assert np.abs(old.predict(X) - new.predict(X)).max() > 1e-3 * np.abs(new.predict(X)).max()


def test_a_file_without_the_bound_loads_with_the_plain_posterior(saved, tmp_path):
    data = json.loads(json.dumps(saved))
    del data["state"]["mixture_"]["bound"]                         # a file older than the bound
    old, new = load_model(_write(data, tmp_path / "old.json")), load_model(_write(saved, tmp_path / "new.json"))
    assert old.mixture_.bound is None and new.mixture_.bound == saved["state"]["mixture_"]["bound"] > 0
    X = new.goal_ + new.scale_ * np.random.default_rng(0).uniform(-3, 3, (500, 2))
    V_old, V_new = old.predict(X), new.predict(X)
    assert np.abs(V_old - V_new).max() > 1e-3 * np.abs(V_old).max()        # tempered somewhere here
    new.mixture_ = with_bound(new.mixture_, None)
    assert np.array_equal(V_old, new.predict(X))


@pytest.mark.parametrize("field, value, match", [("bound", -1.0, "state.mixture_.bound must be a positive number"),
                                                 ("bound", "9", "state.mixture_.bound must be a positive number"),
                                                 ("fade", 0.0, "state.mixture_.fade must be a positive number")])
def test_a_bad_bound_or_rule_is_refused(saved, tmp_path, field, value, match):
    data = json.loads(json.dumps(saved))
    data["state"]["mixture_"][field] = value
    with pytest.raises(ModelFileError, match=match):
        load_model(_write(data, tmp_path / "bad.json"))


def test_an_unknown_mixture_field_is_refused(saved, tmp_path):
    data = json.loads(json.dumps(saved))
    data["state"]["mixture_"]["temperature"] = 2.0
    with pytest.raises(ModelFileError, match=r"unknown field state\.mixture_\.temperature"):
        load_model(_write(data, tmp_path / "bad.json"))

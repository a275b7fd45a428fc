"""The CDSP learner: known contracting systems, a LASA fit, certificates, model files, errors."""
import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sosdyn as sd

@pytest.fixture(scope="module")
def linear_fit(linear_demos):
    return sd.CDSP(warp="none", n_components=1, gamma=0.5, solver_method="ica", max_iter=40).fit(linear_demos)


def test_recovers_a_system_that_needs_a_learned_metric(linear_fit, linear_demos, linear_system):
    A_TRUE, _ = linear_system
    demos = linear_demos
    X, Xd = demos.stacked()
    rel = np.linalg.norm(linear_fit.predict(X) - Xd) / np.linalg.norm(Xd)
    assert rel < 0.02
    assert linear_fit.certified_ and linear_fit.verification_.passed
    # the learned metric certifies the TRUE system at the learned rate
    P = linear_fit.W_[:, :, 0]
    G = A_TRUE.T @ P + P @ A_TRUE + linear_fit.gamma * P
    assert np.linalg.eigvals(np.linalg.solve(P, G)).real.max() < 1e-3
    assert not np.allclose(P / np.trace(P), np.eye(2) / 2, atol=0.05)
    # the identity metric (SEDS-like) cannot fit it
    seds = sd.CDSP(warp="none", n_components=1, gamma=0.5, metric="identity").fit(demos)
    rel_seds = np.linalg.norm(seds.predict(X) - Xd) / np.linalg.norm(Xd)
    assert rel_seds > 5 * rel


def test_ica_cost_never_increases_and_history_is_recorded(linear_fit):
    costs = [h["cost"] for h in linear_fit.history_]
    # non-increasing up to the solver's tolerance (1e-6 of the starting cost)
    assert all(b <= a + 1e-6 * costs[0] for a, b in zip(costs, costs[1:]))
    assert costs[-1] < 0.05 * costs[0]
    assert {"step", "cost", "status", "solve_s", "build_s"} <= set(linear_fit.history_[1])


def test_paper_polynomial_metric_collapses_for_linear_subsystems(linear_demos):
    m = sd.CDSP(warp="none", n_components=1, gamma=0.5, metric_degree=2, max_iter=5).fit(linear_demos)
    diag = m.metric_collapse_
    assert diag["constant_metric_certifies"] is True
    assert diag["max_eig_with_constant_metric"] <= 1e-7


def test_save_load_round_trip_is_exact_and_tampering_is_refused(linear_fit, tmp_path):
    p1, p2 = tmp_path / "m1.json", tmp_path / "m2.json"
    linear_fit.save(p1)
    loaded = sd.load_model(p1)
    loaded.save(p2)
    assert p1.read_bytes() == p2.read_bytes()
    X = np.random.default_rng(0).normal(size=(50, 2)) * 5
    np.testing.assert_array_equal(loaded.predict(X), linear_fit.predict(X))
    data = json.loads(p1.read_text())
    data["state"]["C_"][0][0][0] += 10.0                   # edit an array, keep the old checksum
    (tmp_path / "edited.json").write_text(json.dumps(data))
    with pytest.raises(sd.ModelFileError, match="checksum"):
        sd.load_model(tmp_path / "edited.json")
    # a forger who also recomputes the checksum is stopped by the certificate check
    from sosdyn.lfd.model.fileformat import _digest
    data.pop("sha256")
    data["state"]["C_"][0][0][0] = 50.0                     # an expanding field
    data["sha256"] = _digest(data)
    (tmp_path / "forged.json").write_text(json.dumps(data))
    with pytest.raises(sd.ModelFileError, match="does not check out"):
        sd.load_model(tmp_path / "forged.json")
    (tmp_path / "truncated.json").write_text(p1.read_text()[:200])
    with pytest.raises(sd.ModelFileError, match="corrupt or truncated"):
        sd.load_model(tmp_path / "truncated.json")


def test_same_seed_same_model(tmp_path, linear_demos):
    demos = linear_demos
    a = sd.CDSP(warp="none", n_components=2, gamma=0.5, random_state=3).fit(demos)
    b = sd.CDSP(warp="none", n_components=2, gamma=0.5, random_state=3).fit(demos)
    a.save(tmp_path / "a.json")
    b.save(tmp_path / "b.json")
    strip = lambda p: {k: v for k, v in json.loads(p.read_text())["state"].items() if k != "timings_" and k != "history_"}  # noqa: E731
    assert strip(tmp_path / "a.json") == strip(tmp_path / "b.json")


def batched_final_states(model, starts, horizon):
    m, n = starts.shape
    rhs = lambda _, y: model.predict(y.reshape(m, n)).ravel()  # noqa: E731
    sol = solve_ivp(rhs, (0, horizon), starts.ravel(), method="RK45", rtol=1e-6, atol=1e-6)
    assert sol.success
    return sol.y[:, -1].reshape(m, n)


def test_lasa_fit_converges_from_a_grid_over_twice_the_data_box():
    demos = sd.load_lasa("Leaf_2").subsample(10)
    model = sd.CDSP(warp="none", n_components=3, field_degree=3, metric_degree=2, solver_method="ica",
                    max_iter=6).fit(demos)
    assert model.certified_
    X = np.vstack([d.pos for d in demos])
    lo, hi = X.min(0), X.max(0)
    c, r = (lo + hi) / 2, (hi - lo)                    # twice the box: center +- box size
    g = np.linspace(-1, 1, 10)
    starts = np.array([[c[0] + a * r[0], c[1] + b * r[1]] for a in g for b in g])
    final = batched_final_states(model, starts, horizon=60.0)
    dist = np.linalg.norm(final - model.goal_, axis=1)
    assert (dist < 1.0).all(), f"{(dist >= 1.0).sum()} of 100 starts did not reach the goal (mm)"
    # cubic fields under a learned polynomial metric beat the identity metric (SEDS-like)
    Xa, Xd = demos.stacked()
    seds = sd.CDSP(warp="none", n_components=3, metric="identity").fit(demos)
    rmse = lambda m: np.sqrt(((m.predict(Xa) - Xd) ** 2).sum(1).mean())  # noqa: E731
    assert rmse(model) < 0.9 * rmse(seds)


def test_cubic_fields_with_polynomial_metric_are_certified():
    demos = sd.load_lasa("Leaf_1").subsample(20)
    model = sd.CDSP(warp="none", n_components=2, field_degree=3, metric_degree=2, solver_method="ica",
                    max_iter=4).fit(demos)
    assert model.certified_
    report = model.verify(n_samples=20_000, seed=1)
    assert report.passed and report.max_sampled_eig <= 0 and report.n_samples == 20_000


@pytest.mark.parametrize("kwargs, match", [
    (dict(metric_degree=1), "odd"),
    (dict(field_degree=2), "even"),
    (dict(gamma=-1.0), "gamma"),
    (dict(n_components=0), "n_components"),
    (dict(solver_method="newton"), "solver_method"),
    (dict(metric="cholesky"), "metric"),
])
def test_bad_hyper_parameters_raise_before_any_optimisation(kwargs, match, linear_demos):
    with pytest.raises(sd.InputError, match=match):
        sd.CDSP(**kwargs).fit(linear_demos)


def test_bad_inputs_at_predict_and_rollout(linear_fit):
    with pytest.raises(sd.InputError, match="shape"):
        linear_fit.predict(np.zeros((3, 3)))
    with pytest.raises(sd.InputError, match="NaN"):
        linear_fit.predict(np.array([[np.nan, 0.0]]))
    with pytest.raises(sd.InputError, match="duration"):
        linear_fit.rollout([0.0, 0.0], duration=-1)
    with pytest.raises(sd.NotFittedError):
        sd.CDSP().predict(np.zeros((1, 2)))


def test_rollout_with_push_and_goal_change_converges_to_the_new_goal(linear_fit, linear_system):
    _, GOAL = linear_system
    new_goal = GOAL + np.array([3.0, 2.0])
    traj = linear_fit.rollout([-6.0, 2.0], duration=15.0, dt=0.05,
                              perturbations=[(2.0, np.array([2.0, -2.0]))], goal_changes=[(4.0, new_goal)])
    assert np.linalg.norm(traj.pos[-1] - new_goal) < 1e-2


def test_an_impossible_metric_bound_gives_a_typed_error_with_advice(linear_demos):
    # M >= eps I with eps = 5 contradicts the normalisation trace M(0) = 2
    with pytest.raises(sd.SolverError, match="infeasible.*Try"):
        sd.CDSP(n_components=1, gamma=1.0, eps=5.0, solver_method="ica").fit(linear_demos)


def test_number_of_components_by_bic():
    demos = sd.load_lasa("Angle").subsample(10)
    model = sd.CDSP(warp="none", n_components="bic", solver_method="ica", max_iter=3).fit(demos)
    assert model.n_components_ == 1 + int(np.argmin(model.bic_))
    assert len(model.bic_) == 10 and model.certified_


def test_repr_shows_changed_parameters_and_the_fitted_state(linear_fit):
    assert repr(sd.CDSP()) == "CDSP()"
    assert repr(sd.CDSP(n_components=6, warp="none", gamma=np.float64(0.1))) == "CDSP(n_components=6, warp='none')"
    text = repr(linear_fit)          # CDSP(warp="none", n_components=1, gamma=0.5, max_iter=40) of the linear demos
    assert text.startswith("CDSP(n_components=1, gamma=0.5, max_iter=40, warp='none', fitted: K=1, n=2, goal=[")
    assert text.endswith(", warp=none, certified=True)")
    goal = [float(v) for v in text.split("goal=[")[1].split("]")[0].split(",")]
    assert goal == pytest.approx(linear_fit.goal_, rel=1e-4) and goal == pytest.approx([2.0, -1.0], abs=0.1)

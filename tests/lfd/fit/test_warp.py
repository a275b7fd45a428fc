"""The diffeomorphic pre-warp (sosdyn.lfd.fit.warp) and CDSP fitted through it (CDSP's ``warp``)."""
import hashlib
import json

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.fit import pipeline
from sosdyn.lfd.fit.corrective import rollout_deviation
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.runtime.predictor import warp_back, warp_back2, warp_forward, warp_forward2
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.model.fileformat import canonical
from sosdyn.lfd.rollout import euler_until_rest
from sosdyn.lfd.fit.warp import (
    AUTO_WARPS,
    LIP_FACTOR,
    SIGMA_GRID,
    WARP_DEFAULTS,
    apply,
    check_maps,
    fit_maps,
    invert,
    jacobian,
    line_targets,
    lipschitz_numbers,
    pull_back,
    pulled_back,
    radial_targets,
    stacked_maps,
)

GOAL = np.array([0.3, -0.2])
GRID = np.stack(np.meshgrid(np.linspace(-3, 3, 121), np.linspace(-3, 3, 121)), -1).reshape(-1, 2)


def one_map(lip: float):
    """A single bump centred at (0.5, 0.5), sigma 0.8, with Lipschitz number ``lip``."""
    v = np.array([0.6, 0.8]) * lip * 0.8 / LIP_FACTOR
    return np.array([[0.5, 0.5]]), v[None, :], np.array([0.8]), GOAL


def random_maps(m=6, seed=1):
    rng = np.random.default_rng(seed)
    C, S = rng.normal(size=(m, 2)), rng.uniform(0.3, 1.5, m)
    V = rng.normal(size=(m, 2))
    V *= (rng.uniform(0.3, 0.95, m) * S / (LIP_FACTOR * np.linalg.norm(V, axis=1)))[:, None]
    return C, V, S, GOAL


def test_lipschitz_number_is_the_largest_slope():
    C, V, S, g = one_map(0.7)
    assert lipschitz_numbers(V, S)[0] == pytest.approx(0.7, rel=1e-14)
    J = jacobian(GRID, C, V, S, g)[1] - np.eye(2)      # = v grad rho^T, of norm |v| |grad rho|
    assert np.linalg.norm(J, ord=2, axis=(1, 2)).max() == pytest.approx(0.7, rel=1e-3)


def test_invertible_at_the_bound_and_folding_beyond_it():
    maps = one_map(0.999)
    det = np.linalg.det(jacobian(GRID, *maps)[1])
    assert det.min() >= 1 - 0.999 - 1e-12                # det(I + v grad^T) = 1 + grad.v >= 1 - l
    U = apply(GRID, *maps)
    assert np.abs(invert(U, *maps) - GRID).max() < 1e-9   # injective on the grid: phi^-1(phi(x)) = x
    (c,), (v,), (sig,), g = one_map(0.9)
    x = U[::97].copy()                                  # the plain fixed point x = u - q(x), factor 0.9
    for _ in range(400):
        x = U[::97] - (np.exp(-np.sum((x - c) ** 2, 1) / sig ** 2) - np.exp(-np.sum((g - c) ** 2) / sig ** 2))[:, None] * v
    assert np.abs(x - invert(U[::97], *one_map(0.9))).max() < 1e-12
    folded = one_map(1.5)
    assert np.linalg.det(jacobian(GRID, *folded)[1]).min() < -0.4      # l > 1: the map folds
    with pytest.raises(InputError, match="Lipschitz number 1.5"):
        check_maps(*folded)
    with pytest.raises(InputError, match="Lipschitz"):
        check_maps(*one_map(1.0))


def test_composition_inverse_goal_and_jacobian():
    maps = random_maps()
    X = np.random.default_rng(2).uniform(-2, 2, (50, 2))
    U, J = jacobian(X, *maps)
    assert np.array_equal(U, apply(X, *maps))
    assert np.abs(invert(U, *maps) - X).max() < 1e-10
    assert np.abs(apply(GOAL[None], *maps)[0] - GOAL).max() < 1e-15
    h, fd = 1e-6, np.empty_like(J)
    for i in range(2):
        e = np.zeros(2)
        e[i] = h
        fd[:, :, i] = (apply(X + e, *maps) - apply(X - e, *maps)) / (2 * h)
    assert np.abs(fd - J).max() / np.abs(J).max() < 1e-7
    lip = lipschitz_numbers(maps[1], maps[2])
    sv = np.linalg.svd(jacobian(GRID, *maps)[1], compute_uv=False)
    assert sv[:, -1].min() >= np.prod(1 - lip) and sv[:, 0].max() <= np.prod(1 + lip)


def test_targets():
    curve = np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.5], [0.0, 0.5], [0.0, 0.0]])
    radial = radial_targets(curve, np.zeros(2))
    assert np.allclose(np.linalg.norm(radial, axis=1), [1, 1, 1, 0.5, 0])
    assert np.allclose(radial[1], [1, 0]) and np.allclose(radial[2], [0, 1])
    line = line_targets(curve, np.zeros(2))          # arc lengths 0, 1, 3.5, 4.5, 5 of 5
    assert np.allclose(line[:, 0], [1, 0.8, 0.3, 0.1, 0]) and np.allclose(line[:, 1], 0)


def test_fit_maps_respects_l_max_and_reduces_the_mismatch():
    s = np.linspace(0, 1, 80)
    X = np.column_stack([np.cos(4 * s) * (1 + np.sin(np.pi * s)), np.sin(4 * s) * (1 + np.sin(np.pi * s))]) * (1 - s)[:, None]
    Y = radial_targets(X, np.zeros(2))
    C, V, S = fit_maps(X, Y, np.zeros(2), 40, 0.6, 0.5, 2.0)
    assert 0 < len(S) <= 40 and lipschitz_numbers(V, S).max() <= 0.6 + 1e-12
    before, after = np.abs(Y - X).max(), np.abs(Y - apply(X, C, V, S, np.zeros(2))).max()
    assert after < 0.05 * before                    # measured 0.25 -> 0.0037


def test_fit_maps_is_the_greedy_loop_over_centres_and_sigmas():
    """The vectorised search picks, at every step, the bump the plain double loop over the candidate
    centres and the sigma grid picks (the first one of least error): the same arrays, bit for bit."""
    rng = np.random.default_rng(3)
    X = np.cumsum(rng.normal(size=(60, 2)), axis=0) * 0.1
    Y = radial_targets(X, X[-1], 0.75)
    cur, centers = X.copy(), []
    for _ in range(15):
        best = None
        for i in np.argsort(-np.sum((Y - cur) ** 2, axis=1))[:8]:
            for s in 1.5 * SIGMA_GRID:
                v = 0.5 * (Y - cur)[i]
                v = v * min(1.0, 0.5 * s / (LIP_FACTOR * max(np.linalg.norm(v), 1e-300)))
                new = cur + (np.exp(-np.sum((cur - cur[i]) ** 2, axis=1) / s ** 2)
                             - np.exp(-np.sum((X[-1] - cur[i]) ** 2) / s ** 2))[:, None] * v
                e = float(np.sum((Y - new) ** 2))
                if best is None or e < best[0]:
                    best = (e, cur[i].copy(), new)
        centers.append(best[1])
        cur = best[2]
    C, V, S = fit_maps(X, Y, X[-1], 15, 0.5, 0.5, 1.5)
    assert len(S) == 15 and np.array_equal(C, np.array(centers))
    assert np.array_equal(apply(X, C, V, S, X[-1]), cur)


def test_per_row_maps_are_each_rows_own_warp():
    """stacked_maps: three blocks (a warp, none, another warp) through one pulled_back call give,
    bit for bit, each block through its own warp (the field itself for none)."""
    (C1, V1, S1, _), (C2, V2, S2, _) = random_maps(6, 1), random_maps(4, 2)
    Z = np.random.default_rng(5).uniform(-1, 1, (6, 2))
    f = lambda U: np.column_stack([-U[:, 0] + U[:, 1] ** 2, -2 * U[:, 1]])    # noqa: E731
    both = pulled_back(Z, stacked_maps([(C1, V1, S1), None, (C2, V2, S2)], 2, 2), f)
    alone = np.vstack([pulled_back(Z[:2], (C1, V1, S1), f), f(Z[2:4]), pulled_back(Z[4:], (C2, V2, S2), f)])
    assert np.array_equal(both, alone)
    U, J = jacobian(Z[:2], C1, V1, S1, np.zeros(2))
    np.testing.assert_allclose(both[:2], np.linalg.solve(J, f(U)[:, :, None])[:, :, 0], rtol=1e-13, atol=1e-15)
    assert stacked_maps([None, None], 3, 2) is None


def test_a_prepared_pull_back_called_again_gives_a_fresh_calls_numbers():
    """pull_back reuses its arrays from call to call (an Euler rollout calls it every step): a second
    and third call on other states give, bit for bit, what a fresh pulled_back gives, and the first
    result is not overwritten; the identity of a warp with no maps is the field itself."""
    C, V, S, _ = random_maps(7, 3)
    f = lambda U: np.column_stack([-U[:, 0] + U[:, 1] ** 2, -2 * U[:, 1]])    # noqa: E731
    pull = pull_back((C, V, S), 5)
    rng = np.random.default_rng(9)
    Z1, Z2 = rng.uniform(-1, 1, (5, 2)), rng.uniform(-1, 1, (5, 2))
    first = pull(Z1, f)
    kept = first.copy()
    assert np.array_equal(pull(Z2, f), pulled_back(Z2, (C, V, S), f))
    assert np.array_equal(pull(Z1, f), kept) and np.array_equal(first, kept)
    assert np.array_equal(pull_back((C[:0], V[:0], S[:0]), 5)(Z1, f), f(Z1))


CDSP_SMALL = {"n_components": 3, "max_samples": 300, "verify_samples": 500}


@pytest.fixture(scope="module")
def hook_models(hook_demos):
    demos = hook_demos
    # without the speed floor: the warp's effect alone (the floor speeds the crawling plain fit up, 94.8 < 100)
    return demos, *(CDSP(**CDSP_SMALL, warp=w, speed_floor="none").fit(demos) for w in ("none", {}))


def test_warped_model_follows_the_hook(hook_models):
    demos, plain, warped = hook_models
    scores = {}
    for name, m in (("plain", plain), ("warped", warped)):
        reps = euler_until_rest(m.predict, np.array([d.pos[0] for d in demos]), dt=0.02, max_steps=2000,
                                vel_tol=1e-3, window=4)
        scores[name] = (np.mean([dtwd(r, d.pos).total for r, d in zip(reps, demos)]),
                        np.mean([rollout_deviation(r, d.pos) for r, d in zip(reps, demos)]))
    # measured: plain DTWD 122, deviation 0.29; warped (defaults: <= 100 maps, decay 0.75) 16, 0.07
    assert scores["plain"][0] > 100 and scores["warped"][0] < 0.25 * scores["plain"][0], scores
    assert scores["warped"][1] < 0.4 * scores["plain"][1], scores
    assert plain.certified_ and warped.certified_ and plain.warp_ is None
    assert 0 < len(warped.warp_["sigmas"]) <= 100


def maps_of(m):
    return m.warp_["centers"], m.warp_["vectors"], m.warp_["sigmas"]


def test_predict_is_the_pulled_back_field_and_the_goal_an_equilibrium(hook_models):
    demos, _, m = hook_models
    X = np.random.default_rng(0).uniform(-2, 2, (40, 2))
    Z = (X - m.goal_) / m.scale_
    U, J = jacobian(Z, *maps_of(m), np.zeros(2))
    core = pipeline.core_field(U, m.mixture_, m.C_, m.field_exps_)
    expected = np.array([np.linalg.solve(J[i], core[i]) for i in range(len(X))]) * m.scale_
    assert np.abs(m.predict(X) - expected).max() <= 1e-12 * np.abs(expected).max()
    step = m.predictor()
    P = np.array([step(x) for x in X])
    assert np.abs(P - expected).max() <= 1e-13 * np.abs(expected).max()
    assert np.array_equal(m.goal_, demos.goal) and np.abs(m.predict(m.goal_)).max() < 1e-14
    moved = np.array([0.4, -0.3])
    assert np.abs(m.field(moved[None], moved)).max() < 1e-14     # a new goal is the new equilibrium
    rep = m.verification_.warp
    assert m.verification_.passed and rep["max_lipschitz"] <= 0.5 + 1e-12
    assert rep["min_singular"] >= rep["singular_bound"] > 0 and "warp:" in str(m.verification_)


def test_an_edited_map_fails_the_check(hook_models):
    _, _, m = hook_models
    saved = m.warp_
    try:
        m.warp_ = dict(saved, vectors=saved["vectors"] * 2.5)    # l_j > 1 wherever l_j was > 0.4
        rep = m.verify(n_samples=500)
        assert not rep.passed and rep.warp["max_lipschitz"] > 1
    finally:
        m.warp_ = saved
    assert m.verify(n_samples=500).passed


def test_auto_keeps_the_candidate_of_lowest_training_score(hook_models):
    """On the hook no constant metric sees the distance decrease: a warp must win, by a wide margin;
    the kept model is exactly the fit with the winning candidate's settings."""
    demos = hook_models[0]
    auto = CDSP(**CDSP_SMALL).fit(demos)
    scores = auto.warp_scores_
    assert set(scores) == {"none", *AUTO_WARPS}
    best = min(scores, key=scores.get)
    assert best != "none" and scores["none"] > 2 * scores[best], scores    # measured 0.29 vs ~0.07
    fixed = CDSP(**CDSP_SMALL, warp=AUTO_WARPS[best]).fit(demos)
    X = np.random.default_rng(4).uniform(-2, 2, (50, 2))
    assert np.array_equal(auto.predict(X), fixed.predict(X))
    assert auto.warp == "auto" and auto.verification_.passed


def test_auto_fits_each_distinct_warp_once(hook_models, monkeypatch):
    """Two candidates whose greedy fits give the same bumps (here: the same settings) share one core
    fit and one score; a third, different one gets its own."""
    monkeypatch.setattr(pipeline, "AUTO_WARPS", {"a": dict(WARP_DEFAULTS, n_maps=10), "b": dict(
        WARP_DEFAULTS, n_maps=10), "c": dict(WARP_DEFAULTS, n_maps=5)})
    calls = []
    core = pipeline.fit_core
    monkeypatch.setattr(pipeline, "fit_core", lambda *a: calls.append(a[1]) or core(*a))
    scores = CDSP(**CDSP_SMALL).fit(hook_models[0]).warp_scores_
    assert [None if m is None else len(m[0][2]) for m in calls] == [None, 10, 5]
    assert scores["a"] == scores["b"] != scores["c"] and np.isfinite(list(scores.values())).all()


def test_auto_keeps_no_warp_where_it_reproduces_best(linear_demos):
    """Demonstrations of a contracting linear system: the plain fit reproduces them almost exactly."""
    auto = CDSP(n_components=2, max_samples=300, verify_samples=500).fit(linear_demos)
    scores = auto.warp_scores_
    assert min(scores, key=scores.get) == "none" and auto.warp_ is None, scores


@pytest.mark.parametrize("warp", [{"n_maps": -1}, {"n_maps": 2.5}, {"n_maps": True}, {"l_max": 1.0},
                                  {"l_max": 0}, {"beta": 0}, {"beta": 1.5}, {"decay": 1.5}, {"n_points": 3},
                                  {"match": "median"}, {"target": "circle"}, {"n_map": 10}, {"twist": -1.0},
                                  {"twist": np.inf}, {"twist": True}, {"twist": 2e6}, "yes", 3, None])
def test_bad_warp_parameters_are_input_errors_before_fitting(warp, monkeypatch, hook_demos):
    monkeypatch.setattr("sosdyn.lfd.fit.pipeline.fit_joint_gmm", lambda *a: pytest.fail("fitted"))
    with pytest.raises(InputError, match="Try:"):
        CDSP(warp=warp).fit(hook_demos)


def test_save_load_round_trip_and_tampering(hook_models, tmp_path):
    _, _, m = hook_models
    path = m.save(tmp_path / "hook.json")
    back = load_model(path)
    X = np.random.default_rng(3).uniform(-2, 2, (30, 2))
    assert np.abs(back.predict(X) - m.predict(X)).max() <= 1e-12 * np.abs(m.predict(X)).max()
    assert back.certified_ and back.verification_.warp["passed"] and np.array_equal(back.goal_, m.goal_)
    doc = json.loads(path.read_text())
    doc["state"]["warp_"]["vectors"][0] = [10.0 * x for x in doc["state"]["warp_"]["vectors"][0]]   # l_0 > 1
    doc.pop("sha256")
    doc["sha256"] = hashlib.sha256(canonical(doc)).hexdigest()       # a deliberate edit, checksum redone
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="Lipschitz number"):
        load_model(path)
    doc["state"]["warp_"]["sigmas"] = doc["state"]["warp_"]["sigmas"][:-1]       # shapes disagree
    doc.pop("sha256")
    doc["sha256"] = hashlib.sha256(canonical(doc)).hexdigest()
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="warp_"):
        load_model(path)


def test_a_file_without_a_warp_loads_as_no_warp(hook_models, tmp_path):
    """Files written before the warp existed have neither params.warp nor state.warp_."""
    _, plain, _ = hook_models
    path = plain.save(tmp_path / "plain.json")
    doc = json.loads(path.read_text())
    del doc["params"]["warp"], doc["state"]["warp_"], doc["sha256"]
    doc["sha256"] = hashlib.sha256(canonical(doc)).hexdigest()
    path.write_text(json.dumps(doc))
    back = load_model(path)
    assert back.warp == "none" and back.warp_ is None
    X = np.random.default_rng(5).uniform(-2, 2, (30, 2))
    assert np.array_equal(back.predict(X), plain.predict(X))


def test_rollout_reaches_the_goal_and_a_moved_goal(hook_models):
    demos, _, m = hook_models
    traj = m.rollout(demos[0].pos[0], duration=20.0, dt=0.2)
    assert np.linalg.norm(traj.pos[-1] - m.goal_) < 1e-3
    moved = np.array([0.5, 0.2])
    traj = m.rollout(demos[0].pos[0], duration=20.0, dt=0.2, goal_changes=[(1.0, moved)])
    assert np.linalg.norm(traj.pos[-1] - moved) < 1e-3


@pytest.mark.parametrize("n", [2, 3])
def test_predictor_warp_passes_are_phi_and_the_inverse_jacobian(n):
    """The one-state predictor's float loops (sosdyn.lfd.runtime.predictor): u = phi(z) and J_phi(z)^-1 w by
    rank-one inverses, generic and unrolled for n = 2, against apply / jacobian + solve."""
    rng = np.random.default_rng(n)
    C, S = rng.normal(size=(8, n)), rng.uniform(0.3, 1.5, 8)
    V = rng.normal(size=(8, n))
    V *= (rng.uniform(0.3, 0.95, 8) * S / (LIP_FACTOR * np.linalg.norm(V, axis=1)))[:, None]
    maps = [(tuple(c), tuple(v), 1.0 / s ** 2, float(np.exp(-c @ c / s ** 2))) for c, v, s in zip(C, V, S)]
    passes = [(warp_forward, warp_back)] + ([(warp_forward2, warp_back2)] if n == 2 else [])
    for z in rng.uniform(-2, 2, (20, n)):
        U, J = jacobian(z[None], C, V, S, np.zeros(n))
        w = rng.normal(size=n)
        for forward, back in passes:
            u, grads = forward(maps, z.tolist())
            assert np.abs(np.array(u) - U[0]).max() < 1e-14
            assert np.abs(np.array(back(maps, grads, w.tolist())) - np.linalg.solve(J[0], w)).max() < 1e-12


def test_a_warp_without_bumps_is_no_warp(tmp_path):
    """Straight demonstrations already approach the goal monotonically: no bump lowers the mismatch
    (or n_maps=0), the model is the plain fit, and it saves and loads like one."""
    t = np.linspace(0, 2, 60)
    demos = Demonstrations([Demonstration.from_positions(t, np.outer(1 - t / 2, s), f"line {k}")
                            for k, s in enumerate(([3.0, 1.0], [-2.0, 4.0], [1.0, -3.0]))], "lines")
    plain = CDSP(**CDSP_SMALL, warp="none").fit(demos)
    for warp in ({"n_maps": 0}, {"target": "radial", "decay": 0.0}):
        m = CDSP(**CDSP_SMALL, warp=warp).fit(demos)
        assert m.warp_ is None and np.array_equal(m.C_, plain.C_), warp
        assert load_model(m.save(tmp_path / "m.json")).warp_ is None

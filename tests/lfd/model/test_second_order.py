"""SecondOrderCDSP: known answer, a crossing shape first order cannot follow, convergence from far
away, the certificate refusing forged models, model files and bad input."""
import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sosdyn as sd
from sosdyn.errors import DemonstrationError, InputError, ModelFileError, NotFittedError
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit.second_order.certificate import check_second_order, energy_violations, excursion_bound

A_OSC = np.diag([-9.0, -4.0])           # a lightly damped anisotropic oscillator: frequencies 3 and 2,
B_OSC = -0.6 * np.eye(2)                # decay 0.3/s; its path crosses itself (a damped Lissajous figure)


def oscillator_demos(k=3):
    """Exact demos of x'' = A_OSC x + B_OSC x' (goal 0) from rest at k starts, 20 s each."""
    t = np.linspace(0.0, 20.0, 1001)
    out = []
    for x0 in ([10.0, 8.0], [-9.0, 9.0], [8.0, -10.0])[:k]:
        sol = solve_ivp(lambda _, y: np.concatenate([y[2:], A_OSC @ y[:2] + B_OSC @ y[2:]]), (0, 20.0),
                        np.array(x0 + [0.0, 0.0]), t_eval=t, rtol=1e-10, atol=1e-12)
        out.append(Demonstration.from_positions(t, sol.y[:2].T))
    return Demonstrations(out, name="oscillator")


@pytest.fixture(scope="module")
def linear_model(second_order_system):
    return sd.SecondOrderCDSP(field="mixture", n_components=1, tracking_copies=0, max_iter=5).fit(second_order_system[3])


@pytest.fixture(scope="module")
def crossing():
    return oscillator_demos()


@pytest.fixture(scope="module")
def crossing_model(crossing):
    return sd.SecondOrderCDSP(field="mixture", n_components=1, tracking_copies=0, max_iter=20).fit(crossing)


def test_exported_names():
    assert sd.SecondOrderCDSP is sd.lfd.SecondOrderCDSP


def test_known_linear_system_is_recovered_and_certified(linear_model, second_order_system):
    a_true, b_true, goal, _ = second_order_system
    A, B = linear_model.fields()
    assert np.abs(A[0] - a_true).max() < 0.1 and np.abs(B[0] - b_true).max() < 0.1
    assert np.allclose(linear_model.goal_, goal, atol=1e-3)
    cert = linear_model.certificate_
    assert cert.passed and min(cert.proven_margins) > 0 and cert.metric_min_eig > 0 and max(cert.lmi_max_eigs) < 0
    # the true system's demos never gain energy in the learned metric
    assert linear_model.energy_violations_["energy_gain"] == 0.0


def test_crossing_shape_second_order_follows_first_order_cannot(crossing, crossing_model):
    assert len(sd.lfd.data.crossing.find_crossings(crossing)) > 0
    first = sd.CDSP(warp="none", n_components=6).fit(crossing)
    second = [dtwd(crossing_model.rollout(d.pos[0], d.duration).pos, d.pos).per_point for d in crossing]
    one = [dtwd(first.rollout(d.pos[0], d.duration).pos, d.pos).per_point for d in crossing]
    assert crossing_model.certificate_.passed
    A, B = crossing_model.fields()
    assert np.abs(A[0] - A_OSC).max() < 0.05 and np.abs(B[0] - B_OSC).max() < 0.01
    assert max(second) < 0.1 and min(one) > 1.0, (second, one)       # the figure spans ~20 units


def test_converges_from_far_states_within_the_excursion_bound(crossing_model):
    rng = np.random.default_rng(1)
    for _ in range(3):
        x0, v0 = rng.normal(0, 2000, 2), rng.normal(0, 2000, 2)
        tr = crossing_model.rollout(x0, 200.0, v0=v0, dt=0.5)
        bound = crossing_model.excursion_bound(x0, v0)
        assert np.linalg.norm(tr.pos - crossing_model.goal_, axis=1).max() <= bound * (1 + 1e-6)
        assert np.linalg.norm(tr.pos[-1] - crossing_model.goal_) < 1e-3 * np.linalg.norm(x0)
        assert np.linalg.norm(tr.vel[-1]) < 1e-3 * np.linalg.norm(v0)


def test_pushes_and_goal_changes(linear_model, second_order_system):
    goal = second_order_system[2]
    new_goal = goal + [3.0, 4.0]
    tr = linear_model.rollout(goal + 10, 10.0, perturbations=[(1.0, [1, 1]), (2.0, [0, 0, 5, -5])],
                              goal_changes=[(3.0, new_goal)])
    assert [e["kind"] for e in tr.events] == ["push", "push", "goal_change"]
    assert tr.events[1]["after"][2] - tr.events[1]["before"][2] == 5.0
    assert np.linalg.norm(tr.pos[-1] - new_goal) < 1e-3 and tr.vel.shape == tr.pos.shape
    assert np.allclose(tr.goal_history[-1], new_goal)


def test_predictor_matches_predict(linear_model, second_order_system):
    a_true, b_true, goal, _ = second_order_system
    x, v = goal + [1.0, -2.0], np.array([0.5, 3.0])
    step = linear_model.predictor()
    assert np.allclose(step(x, v), linear_model.predict(x, v)[0])
    assert np.allclose(step(x, v), a_true @ (x - goal) + b_true @ v, atol=0.2)
    assert np.allclose(step(x + 7, v, goal=goal + 7), step(x, v))          # a goal change translates


def test_python_export_matches_predict(linear_model, second_order_system, tmp_path):
    goal = second_order_system[2]
    path = tmp_path / "acc.py"
    path.write_text(linear_model.export("python"))
    space = {}
    exec(compile(path.read_text(), str(path), "exec"), space)
    X, V = np.random.default_rng(3).normal(0, 5, (2, 7, 2))
    assert np.allclose(space["acceleration"](X, V), linear_model.predict(X, V), rtol=1e-12, atol=1e-12)
    step = linear_model.predictor()
    assert np.allclose(space["acceleration"](X[0], V[0], goal=goal + 1), step(X[0], V[0], goal=goal + 1))


def test_certificate_refuses_forged_fields(linear_model, tmp_path):
    C = linear_model.C_.copy()
    C[0, :, 2:] = np.eye(2)            # B = +I: the velocity grows, no metric can certify it
    rep = check_second_order(C, linear_model.M_, linear_model.gamma, linear_model.time_scale_,
                             linear_model.mixture_, 1000, 0)
    assert not rep.passed and max(rep.lmi_max_eigs) > 0 and rep.max_sampled_rate > 0
    path = linear_model.save(tmp_path / "m.json")
    doc = json.loads(path.read_text())
    doc["state"]["C"] = C.tolist()
    from sosdyn.lfd.model.fileformat import write_model_file
    write_model_file({k: doc[k] for k in ("format", "version", "params", "state")}, path)   # a valid checksum
    with pytest.raises(ModelFileError, match="does not check out"):
        sd.load_model(path)


def test_model_file_round_trip(linear_model, tmp_path):
    path = linear_model.save(tmp_path / "m.json")
    loaded = sd.load_model(path)
    assert isinstance(loaded, sd.SecondOrderCDSP) and loaded.certificate_.passed
    X, V = np.random.default_rng(2).normal(0, 5, (2, 10, 2))
    assert np.array_equal(loaded.predict(X, V), linear_model.predict(X, V))
    text = path.read_text()
    path.write_text(text.replace('"time_scale": ', '"time_scale": 1'))
    with pytest.raises(ModelFileError):
        sd.load_model(path)


def test_a_file_that_names_the_solver_method_method_loads(linear_model, tmp_path):
    """Files written before the parameter took the first-order name ``solver_method`` call it ``method``."""
    from sosdyn.lfd.model.fileformat import write_model_file
    doc = json.loads(linear_model.save(tmp_path / "m.json").read_text())
    doc["params"]["method"] = doc["params"].pop("solver_method")
    path = write_model_file({k: doc[k] for k in ("format", "version", "params", "state")}, tmp_path / "old.json")
    loaded = sd.load_model(path)
    assert loaded.get_params() == dict(linear_model.get_params(), random_state=linear_model.seed_)
    doc["params"]["solver_method"] = "ica"                       # both names: not a file sosdyn wrote
    path = write_model_file({k: doc[k] for k in ("format", "version", "params", "state")}, tmp_path / "both.json")
    with pytest.raises(ModelFileError, match="unknown \\['method'\\]"):
        sd.load_model(path)


def test_excursion_bound_and_energy_measure():
    assert excursion_bound(np.eye(4), np.array([3.0, 4.0, 0.0, 0.0])) == pytest.approx(5.0)
    E = np.array([[1.0, 0.0, 1.0, 0.0], [1.0, 0.0, -1.0, 0.0]])     # moving away, moving back
    Edot = np.array([[1.0, 0.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0]])
    out = energy_violations(np.eye(4), 0.1, E, Edot)
    assert out == {"samples": 2, "slower_than_certified": 0.5, "energy_gain": 0.5}


@pytest.mark.parametrize("params", [dict(gamma=-1.0), dict(field="mixture", solver_method="newton"),
                                    dict(field="mixture", tracking_copies=1.5), dict(field="mixture", tracking_sigma=0.0),
                                    dict(field="mixture", n_components=0), dict(solver=""), dict(field="spline"),
                                    dict(position_width=0.0), dict(tank_factor=-1.0), dict(n_components=3),
                                    dict(field="mixture", velocity_width=0.5)])
def test_bad_parameters_are_refused_before_fitting(params, second_order_system):
    with pytest.raises(InputError):
        sd.SecondOrderCDSP(**params).fit(second_order_system[3])


def test_bad_input(linear_model):
    with pytest.raises(NotFittedError):
        sd.SecondOrderCDSP().predict([0, 0], [0, 0])
    with pytest.raises(DemonstrationError):
        sd.SecondOrderCDSP().fit([])
    with pytest.raises(InputError):
        linear_model.predict(np.zeros((3, 2)), np.zeros((2, 2)))
    with pytest.raises(InputError):
        linear_model.predict([0, np.nan], [0, 0])
    with pytest.raises(InputError):
        linear_model.rollout([0, 0], 1.0, perturbations=[(0.5, [1, 2, 3])])
    with pytest.raises(InputError):
        linear_model.rollout([0, 0], 1.0, goal_changes=[(0.5, [1, 2, 3, 4])])
    with pytest.raises(InputError):
        linear_model.verify(n_samples=10)
    with pytest.raises(InputError):
        linear_model.verify(seed=-1)


def alpha_demos(k=5, T=300, duration=4.0):
    """An "alpha": the nodal cubic (u^2 - 1, u (u^2 - 1)) x 50 for u from about -1.6 to 1.2 on a
    minimum-jerk time law (rest at both ends); it crosses itself near u = -1, 1 (15 crossing pairs)."""
    rng = np.random.default_rng(0)
    out = []
    for _ in range(k):
        t = np.linspace(0.0, duration, T)
        s = t / duration
        a = 1.6 + 0.1 * rng.standard_normal()
        u = -a + (a + 1.2) * (10 * s**3 - 15 * s**4 + 6 * s**5)
        x = np.column_stack([u**2 - 1, u * (u**2 - 1)]) * 50 * (1.0 + 0.05 * rng.standard_normal())
        out.append(Demonstration.from_positions(t, x - x[-1]))
    return Demonstrations(out, name="alpha")


@pytest.mark.slow
def test_alpha_second_order_beats_first_order():
    """docs/theory.md "Second order": on the α, DTWD per point 1.2-1.8 for the tracking field (default),
    8.0 for the mixture (K = 8), 7.7 for CDSP() (which cuts the loop)."""
    demos = alpha_demos()
    tracking, mixture = sd.SecondOrderCDSP().fit(demos), sd.SecondOrderCDSP(field="mixture").fit(demos)
    first_model = sd.CDSP().fit(demos)
    second = [[dtwd(m.rollout(d.pos[0], 1.5 * d.duration, v0=d.vel[0]).pos, d.pos).per_point for d in demos]
              for m in (tracking, mixture)]
    first = [dtwd(first_model.rollout(d.pos[0], 1.5 * d.duration).pos, d.pos).per_point for d in demos]
    assert tracking.certificate_.passed and mixture.certificate_.passed
    assert np.mean(second[0]) < 3.0 < 2 * 3.0 < np.mean(first), (second, first)
    assert np.mean(second[1]) < 9.0, second

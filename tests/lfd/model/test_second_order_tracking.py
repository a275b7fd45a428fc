"""SecondOrderCDSP(field="tracking"), the default: a crossing system tracked and certified, the tank
theorem along rollouts (W = V + b <= e^{-2 gamma t} W(0)), a motion that must gain energy (it starts near
the goal and swings out) followed while V rises, model files (round trip, forgeries, older files),
the predictor's tank, the Python and C++ exports, and bad input."""
import json
import shutil
import subprocess

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InputError, ModelFileError
from sosdyn.evaluation.metrics import dtwd
from sosdyn.evaluation.second_order import semi_implicit_until_rest
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.model.fileformat import write_model_file

from test_second_order import oscillator_demos


def swing_demos(k=3):
    """Demos that start near the goal at rest, spiral out counter-clockwise to about 3x their start
    radius and back in to the goal (1.2 turns, minimum-jerk time law, rest at both ends): a constant
    quadratic energy cannot decrease along them."""
    rng = np.random.default_rng(5)
    out = []
    for _ in range(k):
        t = np.linspace(0.0, 4.0, 400)
        s = 10 * (t / 4) ** 3 - 15 * (t / 4) ** 4 + 6 * (t / 4) ** 5
        rho = (0.3 * (1 - s) + 3.0 * s * (1 - s)) * 10 * (1 + 0.03 * rng.standard_normal())
        phi = 2 * np.pi * 1.2 * s + 0.05 * rng.standard_normal()
        out.append(Demonstration.from_positions(t, np.column_stack([rho * np.cos(phi), rho * np.sin(phi)])))
    return Demonstrations(out, name="swing")


@pytest.fixture(scope="module")
def swing_model():
    return sd.SecondOrderCDSP().fit(swing_demos())


@pytest.fixture(scope="module")
def oscillator_model():
    return sd.SecondOrderCDSP().fit(oscillator_demos())


def energies(model, X, V, B):
    """(V(e), V(e) + b) along states (rows)."""
    s, T = model.length_scale_, model.time_scale_
    E = np.hstack([(X - model.goal_) / s, V * T / s])
    Vm = np.einsum("ti,ij,tj->t", E, model.M_, E)
    return Vm, Vm + B


def semi_implicit(model, x0, v0, duration, dt):
    """(X, V, B) of a semi-implicit Euler rollout with the tank (explicit Euler, kept >= 0)."""
    X, V = np.array([x0], float), np.array([v0], float)
    B = model.initial_tank(X, V)
    rows = [(X[0], V[0], B[0])]
    for _ in range(int(duration / dt)):
        A, rate = model.derivatives(X, V, model.goal_, B)
        V = V + dt * A
        X = X + dt * V
        B = np.maximum(0.0, B + dt * rate)
        rows.append((X[0], V[0], B[0]))
    return tuple(np.array(c) for c in zip(*rows))


def test_a_crossing_system_is_tracked_and_certified(oscillator_model):
    demos = oscillator_demos()
    assert len(sd.lfd.data.crossing.find_crossings(demos)) > 0
    m = oscillator_model
    assert m.certified_ and m.field == "tracking" and m.tank_ is not None and m.verify().passed
    dev = [dtwd(m.rollout(d.pos[0], d.duration, v0=d.vel[0]).pos, d.pos).per_point for d in demos]
    assert max(dev) < 0.4, dev                           # 2 % of the figure's ~20 units (first order: > 1)


def test_tank_theorem_holds_along_rollouts_from_far_away(oscillator_model):
    m = oscillator_model
    rng = np.random.default_rng(7)
    g = m.gamma
    for _ in range(2):
        x0, v0 = m.goal_ + rng.normal(0, 30, 2), rng.normal(0, 30, 2)
        X, V, B = semi_implicit(m, x0, v0, 30.0, 2e-3)
        _, W = energies(m, X, V, B)
        t = np.arange(len(W)) * 2e-3
        assert np.all(W <= W[0] * np.exp(-2 * g * t) * (1 + 2e-2))          # dW/dt <= -2 gamma W (Euler: 2 %)
        assert np.linalg.norm(X - m.goal_, axis=1).max() <= m.excursion_bound(x0, v0) * (1 + 1e-2)
        assert np.linalg.norm(X[-1] - m.goal_) < 1e-2 * np.linalg.norm(x0 - m.goal_)


def test_a_motion_that_gains_energy_is_followed(swing_model):
    demos, m = swing_demos(), swing_model
    assert m.certified_ and m.tank_.beta > 0 and m.tank_needs_.max() > 0    # the demos need the tank
    for d in demos:
        X, V, B = semi_implicit(m, d.pos[0], d.vel[0], 1.5 * d.duration, 2e-3)
        Vm, W = energies(m, X, V, B)
        assert Vm.max() > 2 * Vm[0]                                          # V rises: the tank pays
        assert np.all(np.diff(W) <= 1e-9 * W[:-1])                           # W never does
        assert dtwd(X[::5], d.pos).per_point < 0.05 * np.ptp(d.pos, axis=0).max()
        assert np.linalg.norm(X[-1] - m.goal_) < 0.01 * np.ptp(d.pos, axis=0).max()


def test_model_file_round_trip_and_forgeries(oscillator_model, tmp_path):
    m = oscillator_model
    path = m.save(tmp_path / "m.json")
    loaded = sd.load_model(path)
    assert loaded.field == "tracking" and loaded.certified_ and loaded.tank_.beta == m.tank_.beta
    X, V = np.random.default_rng(2).normal(0, 5, (2, 10, 2))
    assert np.array_equal(loaded.predict(X, V), m.predict(X, V))
    doc = json.loads(path.read_text())

    def forged(edit):
        d = json.loads(json.dumps(doc))
        edit(d["state"])
        return write_model_file({k: d[k] for k in ("format", "version", "params", "state")}, tmp_path / "f.json")
    with pytest.raises(ModelFileError, match="does not check out"):          # the witness B = +I
        sd.load_model(forged(lambda st: st["C"][0][0].__setitem__(2, 5.0) or st["C"][0][1].__setitem__(3, 5.0)))
    with pytest.raises(ModelFileError, match="beta"):
        sd.load_model(forged(lambda st: st.__setitem__("beta", -1.0)))
    with pytest.raises(ModelFileError, match="sample_accelerations"):
        sd.load_model(forged(lambda st: st.__setitem__("sample_accelerations", st["sample_accelerations"][1:])))
    with pytest.raises(ModelFileError, match="weights"):                      # a mixture's field in a tracking state
        sd.load_model(forged(lambda st: st.__setitem__("weights", [1.0])))


def test_files_without_the_field_parameter_are_mixtures(second_order_system, tmp_path):
    model = sd.SecondOrderCDSP(field="mixture", n_components=1, tracking_copies=0, max_iter=3).fit(second_order_system[3])
    doc = json.loads(model.save(tmp_path / "m.json").read_text())
    for k in ("field", "position_width", "velocity_width", "tank_factor"):
        del doc["params"][k]
    old = write_model_file({k: doc[k] for k in ("format", "version", "params", "state")}, tmp_path / "old.json")
    loaded = sd.load_model(old)
    assert loaded.field == "mixture" and loaded.tank_ is None
    X, V = np.random.default_rng(1).normal(0, 3, (2, 5, 2))
    assert np.array_equal(loaded.predict(X, V), model.predict(X, V))


def test_predictor_keeps_and_advances_the_tank(oscillator_model):
    m = oscillator_model
    x, v = m.goal_ + [4.0, -3.0], np.array([2.0, 1.0])
    step = m.predictor()
    a0 = step(x, v)
    b0 = float(m.initial_tank(x[None], v[None])[0])
    assert step.tank == b0 and np.allclose(a0, m.predict(x, v)[0])
    step(x, v, dt=0.01)
    rate = m.derivatives(x[None], v[None], m.goal_, np.array([b0]))[1][0]
    assert step.tank == pytest.approx(max(0.0, b0 + 0.01 * rate), rel=1e-12)
    step.reset()
    step(x + 1, v)
    assert step.tank == pytest.approx(float(m.initial_tank((x + 1)[None], v[None])[0]))


def test_python_export_evaluates_the_model_with_its_tank(oscillator_model, tmp_path):
    m = oscillator_model
    space = {}
    path = tmp_path / "acc.py"
    path.write_text(m.export("python"))
    exec(compile(path.read_text(), str(path), "exec"), space)
    rng = np.random.default_rng(3)
    X, V, B = m.goal_ + rng.normal(0, 8, (9, 2)), rng.normal(0, 8, (9, 2)), rng.uniform(0, 0.5, 9)
    A, rate = space["derivatives"](X, V, B)
    want_A, want_rate = m.derivatives(X, V, m.goal_, B)
    np.testing.assert_allclose(A, want_A, rtol=1e-12, atol=1e-12 * np.abs(want_A).max())
    np.testing.assert_allclose(rate, want_rate, rtol=1e-12, atol=1e-12 * np.abs(want_rate).max())
    np.testing.assert_allclose(space["acceleration"](X, V), m.predict(X, V), rtol=1e-12)
    np.testing.assert_allclose(space["initial_tank"](X, V), m.initial_tank(X, V), rtol=1e-12)


MAIN = """#include "model.hpp"
#include <cstdio>
int main() {
  constexpr int P = second_order_model::P;
  double x[P], v[P], a[P], c[P], tank, dt;
  for (;;) {
    for (double* row : {x, v})
      for (int i = 0; i < P; ++i) if (std::scanf("%lf", &row[i]) != 1) return 0;
    if (std::scanf("%lf %lf", &tank, &dt) != 2) return 0;
    const bool ok = second_order_model::acceleration(x, v, a) && second_order_model::acceleration(x, v, c, &tank, dt);
    for (int i = 0; i < P; ++i) std::printf("%.17g %.17g ", a[i], c[i]);
    std::printf("%.17g %.17g %d\\n", second_order_model::initial_tank(x, v), tank, ok ? 1 : 0);
  }
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_cpp_export_matches_the_model(oscillator_model, tmp_path):
    """Compiled with -Wall -Wextra -Werror: the full-tank overload gives predict, the tank overload the
    filtered acceleration and one Euler step of the tank, to 1e-9 relative."""
    m = oscillator_model
    (tmp_path / "model.hpp").write_text(m.to_cpp())
    (tmp_path / "main.cpp").write_text(MAIN)
    exe = tmp_path / "main"
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    rng = np.random.default_rng(4)
    X, V, B = m.goal_ + rng.normal(0, 10, (50, 2)), rng.normal(0, 10, (50, 2)), rng.uniform(0, 0.3, 50)
    stdin = "\n".join(" ".join(repr(float(v)) for v in [*x, *v, b, 0.01]) for x, v, b in zip(X, V, B))
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True)
    out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    assert out.shape == (50, 7) and (out[:, -1] == 1).all()
    A, rate = m.derivatives(X, V, m.goal_, B)
    for got, want in ((out[:, [0, 2]], m.predict(X, V)), (out[:, [1, 3]], A)):
        assert np.max(np.abs(got - want) / np.abs(want).max(axis=1, keepdims=True)) < 1e-9
    np.testing.assert_allclose(out[:, 4], m.initial_tank(X, V), rtol=1e-9)
    np.testing.assert_allclose(out[:, 5], np.maximum(0.0, B + 0.01 * rate), rtol=1e-9, atol=1e-12)


def test_evaluation_integrates_the_tank(oscillator_model):
    """The protocol's integrator carries the tank: its path is the hand-written semi-implicit one."""
    m = oscillator_model
    x0, v0 = np.array([[9.0, 7.0]]), np.array([[0.0, 0.0]])
    paths = semi_implicit_until_rest(lambda X, V, B: m.derivatives(X, V, m.goal_, B), x0, v0, dt=0.01,
                                     max_steps=300, vel_tol=1e-9, window=4, B0=m.initial_tank(x0, v0))
    X, _, _ = semi_implicit(m, x0[0], v0[0], 3.0, 0.01)
    np.testing.assert_allclose(paths[0], X[:len(paths[0])], rtol=1e-12, atol=1e-12)


def test_bad_input_is_refused(oscillator_model):
    m = oscillator_model
    with pytest.raises(InputError, match="tank"):
        m.predict([0.0, 0.0], [0.0, 0.0], tank=-1.0)
    with pytest.raises(InputError, match="tank"):
        m.predict(np.zeros((3, 2)), np.zeros((3, 2)), tank=[0.1, 0.2])
    with pytest.raises(InputError, match="applies to field='mixture' only"):
        sd.SecondOrderCDSP(max_iter=3).fit(oscillator_demos(1))
    with pytest.raises(InputError, match="applies to field='tracking' only"):
        sd.SecondOrderCDSP(field="mixture", tank_factor=2.0).fit(oscillator_demos(1))

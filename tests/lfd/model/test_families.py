"""One interface, three families: every method of MotionModel works on CDSP, PoseCDSP and
SecondOrderCDSP alike (known systems, so the answers are checked, not just the types)."""
import shutil
import subprocess

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import sosdyn as sd
from sosdyn.errors import InputError
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations
from sosdyn.lfd.model import FAMILIES, MotionModel, family_for
from sosdyn.lfd.rollout.quality import deviation

from export_support import import_source

X_GOAL, R_GOAL = np.array([0.4, -0.2, 0.3]), Rotation.from_rotvec([0.3, -0.5, 0.2])


def pose_demos():
    """xdot = -0.8 (x - x_g), rdot = -0.8 r in the chart at R_g, from 8 starts (tests/lfd/model/test_pose.py)."""
    rng, t = np.random.default_rng(3), np.linspace(0.0, 12.0, 240)
    decay = np.exp(-0.8 * t)[:, None]
    demos = []
    for i in range(8):
        x0, r0 = X_GOAL + 0.4 * rng.normal(size=3), 1.2 * rng.uniform(-1, 1, size=3)
        demos.append(PoseDemonstration(t, X_GOAL + decay * (x0 - X_GOAL),
                                       (R_GOAL * Rotation.from_rotvec(decay * r0)).as_quat(scalar_first=True), f"s{i}"))
    return PoseDemonstrations(demos, "known", "m")


@pytest.fixture(scope="module", params=["first", "pose", "second", "tracking"])
def case(request, linear_demos, second_order_system):
    """(model, its demonstrations, a start x0, a goal to move to) for each family."""
    if request.param == "first":
        model = sd.CDSP(n_components=2, warp="none").fit(linear_demos)
        return model, linear_demos, linear_demos[0].pos[0], linear_demos.goal + [1.0, -1.0]
    if request.param == "pose":
        demos = pose_demos()
        model = sd.PoseCDSP(n_components=1, warp="none", max_samples=400).fit(demos)
        start = np.concatenate([demos[0].pos[0], demos[0].quat[0]])
        return model, demos, start, np.concatenate([X_GOAL + 0.1, R_GOAL.as_quat(scalar_first=True)])
    demos = second_order_system[3]
    model = (sd.SecondOrderCDSP(field="mixture", n_components=1, tracking_copies=0, max_iter=5)
             if request.param == "second" else sd.SecondOrderCDSP()).fit(demos)
    return model, demos, demos[0].pos[0], demos.goal + [1.0, -1.0]


def positions(model, traj):
    return np.asarray(traj.states)[:, :len(model.names())]


def test_the_families_register_and_are_chosen_by_the_data(case, linear_demos):
    model, demos, _, _ = case
    assert isinstance(model, MotionModel) and FAMILIES[model.file_format] is type(model)
    assert family_for(linear_demos) is sd.CDSP and family_for(linear_demos, 2) is sd.SecondOrderCDSP
    assert family_for(pose_demos()) is sd.PoseCDSP
    with pytest.raises(InputError, match="second-order pose model"):
        family_for(pose_demos(), 2)
    with pytest.raises(InputError, match="order must be 1"):
        family_for(linear_demos, 3)
    assert model.certified_ and model.verify().passed and model.summary()[0]
    assert repr(model).startswith(type(model).__name__ + "(") and "certified=True" in repr(model)


def test_save_load_round_trip_keeps_the_motion(case, tmp_path):
    model, demos, x0, _ = case
    loaded = sd.load_model(model.save(tmp_path / "m.json"))
    assert type(loaded) is type(model) and loaded.certified_ and loaded.units_ == model.units_
    assert loaded.names() == model.names() and loaded.layout() == model.layout()
    a, b = model.rollout(x0, 2.0), loaded.rollout(x0, 2.0)
    np.testing.assert_array_equal(a.states, b.states)


def test_rollout_with_push_goal_change_and_speed_limit(case):
    """Every family: a push at 1 s, a goal change at 2 s, |dx/dt| <= max_speed between the events'
    jumps, the end at the new goal, rows as the layout names them."""
    model, demos, x0, goal = case
    layout = model.layout()
    free = model.rollout(x0, 20.0)
    v_max = 0.3 * float(np.max(np.linalg.norm(np.diff(positions(model, free), axis=0), axis=1) / np.diff(free.t)))
    push = np.zeros(len(layout.pushes[0]))
    push[0] = 0.1
    traj = model.rollout(x0, 40.0, perturbations=[(1.0, push)], goal_changes=[(2.0, goal)], max_speed=v_max)
    pos = positions(model, traj)
    assert traj.states.shape[1] == len(layout.columns) and traj.goal_history.shape[1] == len(layout.goal)
    np.testing.assert_allclose(traj.goal_history[-1], goal)
    speed = np.linalg.norm(np.diff(pos, axis=0), axis=1) / np.diff(traj.t)
    jump = np.argmin(np.abs(traj.t[1:] - 1.0))
    assert np.delete(speed, [jump - 1, jump, jump + 1]).max() <= v_max * 1.01
    assert np.linalg.norm(pos[-1] - goal[:len(pos[-1])]) < 0.05 * np.linalg.norm(x0[:len(pos[-1])] - goal[:len(pos[-1])])


def test_speed_limit_keeps_the_path(case):
    """The limit is a time change of the certified system: the limited path lies on the free one."""
    model, _, x0, _ = case
    free, slow = model.rollout(x0, 30.0, dt=0.01), model.rollout(x0, 300.0, dt=0.01, max_speed=0.05)
    a, b = positions(model, free), positions(model, slow)
    extent = np.linalg.norm(a[0] - a[-1])
    assert deviation(a, b).max() < 0.01 * extent        # each free sample on the (dense) limited path
    assert np.linalg.norm(b[-1] - a[-1]) < 0.01 * extent


def test_score_rows_have_one_layout(case):
    model, demos, _, _ = case
    rows = model.score(demos)
    assert len(rows) == len(demos)
    for row in rows:
        assert {"demo", "mean_dev", "max_dev", "arrival_s", "duration_s", "final_error", "at_goal"} <= set(row)
        assert row["at_goal"] and row["max_dev"] < 0.1 * np.ptp(demos[row["demo"]].pos, axis=0).max()


def test_trajectories_stay_within_the_excursion_bound(case):
    model, _, x0, _ = case
    bound = model.excursion_bound(x0)
    traj = positions(model, model.rollout(x0, 20.0))
    goal = traj[-1] if not hasattr(model, "goal_") else model.goal_
    assert np.isfinite(bound) and np.linalg.norm(traj - goal, axis=1).max() <= bound * (1 + 1e-9)


def test_reproductions_are_what_a_figure_draws(case):
    model, demos, _, _ = case
    view = model.reproductions(demos)
    assert len(view.runs) == len(demos) and view.names == model.names() and view.units == model.units_
    assert (view.field is not None) == (isinstance(model, sd.CDSP) and len(view.goal) == 2)


def test_python_export_evaluates_the_model(case, tmp_path):
    model, demos, x0, goal = case
    module = import_source(model.export("python"), tmp_path / "exported.py")
    if isinstance(model, sd.SecondOrderCDSP):
        x, v = x0 + 0.3, np.array([1.0, -2.0])
        np.testing.assert_allclose(module.acceleration(x, v, goal=goal), model.predictor()(x, v, goal=goal), rtol=1e-12)
    elif isinstance(model, sd.PoseCDSP):
        v, w = module.predict_pose(x0[:3], x0[3:])
        np.testing.assert_allclose(np.concatenate([v, w]), np.concatenate(model.predictor()(x0[:3], x0[3:])), rtol=1e-12)
    else:
        np.testing.assert_allclose(module.predict(x0, goal=goal), model.predictor()(x0, goal=goal), rtol=1e-12)
        assert module.COLUMNS == model.names()


def test_keywords_of_other_families_are_refused_by_name(case):
    model, _, x0, _ = case
    if not isinstance(model, sd.SecondOrderCDSP):
        with pytest.raises(InputError, match=r"v0 does not apply .*SecondOrderCDSP\.rollout takes it"):
            model.rollout(x0, 1.0, v0=np.zeros(len(x0)))
    if not isinstance(model, sd.PoseCDSP):
        with pytest.raises(InputError, match=r"max_angular_speed does not apply .*PoseCDSP"):
            model.to_python(max_angular_speed=1.0)
    with pytest.raises(InputError, match="no model takes it"):
        model.predictor(speed=1.0)
    with pytest.raises(InputError, match="unknown export target 'rust'"):
        model.export("rust")


@pytest.mark.parametrize("namespace", ["class", "int", "namespace", "std", "a__b", "_x", "x-y", ""])
def test_cpp_namespaces_that_do_not_compile_are_refused(case, namespace):
    with pytest.raises(InputError, match="namespace"):
        case[0].to_cpp(namespace=namespace)


def test_second_order_speed_limit_is_for_rollouts_only(case):
    model = case[0]
    if not isinstance(model, sd.SecondOrderCDSP):
        pytest.skip("first-order and pose controllers take the limit")
    for call in (lambda: model.predictor(max_speed=1.0), lambda: model.to_python(max_speed=1.0),
                 lambda: model.to_cpp(max_speed=1.0)):
        with pytest.raises(InputError, match="time change"):
            call()


MAIN_SECOND_ORDER = """#include "model.hpp"
#include <cstdio>
int main() {
  constexpr int P = second_order_model::P;
  double x[P], v[P], g[P], a[P], b[P];
  for (;;) {
    for (double* row : {x, v, g})
      for (int i = 0; i < P; ++i) if (std::scanf("%lf", &row[i]) != 1) return 0;
    const bool ok = second_order_model::acceleration(x, v, a) && second_order_model::acceleration(x, v, b, g);
    for (int i = 0; i < P; ++i) std::printf("%.17g %.17g ", a[i], b[i]);
    std::printf("%d\\n", ok ? 1 : 0);
  }
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_second_order_cpp_export_matches_predict(second_order_system, tmp_path):
    """The C++ header, compiled with -Wall -Wextra -Werror, gives predict's accelerations to 1e-9
    relative at the model's goal and at a moved one; a state that is not finite gives false."""
    demos = second_order_system[3]
    model = sd.SecondOrderCDSP(field="mixture", n_components=3, max_iter=3).fit(demos)
    (tmp_path / "model.hpp").write_text(model.to_cpp())
    (tmp_path / "main.cpp").write_text(MAIN_SECOND_ORDER)
    exe = tmp_path / "main"
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    rng = np.random.default_rng(4)
    X, V = model.goal_ + rng.normal(0, 10, (200, 2)), rng.normal(0, 20, (200, 2))
    G = model.goal_ + rng.normal(0, 5, (200, 2))
    stdin = "\n".join(" ".join(repr(float(v)) for v in np.concatenate(row)) for row in zip(X, V, G))
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True)
    out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    assert out.shape == (200, 5) and (out[:, -1] == 1).all()
    own, moved = out[:, [0, 2]], out[:, [1, 3]]
    expected_moved = np.array([model.predictor()(x, v, goal=g) for x, v, g in zip(X, V, G)])
    for got, want in ((own, model.predict(X, V)), (moved, expected_moved)):
        assert np.max(np.abs(got - want) / np.abs(want).max(axis=1, keepdims=True)) < 1e-9
    bad = subprocess.run([str(exe)], input="nan 0 0 0 0 0\n", capture_output=True, text=True, check=True)
    assert bad.stdout.split()[-1] == "0"

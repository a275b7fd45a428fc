"""Run-time goal and speed limit: the predictor, the Python export and the C++ export equal the
model with its goal moved (the goal-shifted field translated), and a speed limit keeps the
directions, the paths and the goal while bounding |xdot|."""
import shutil
import subprocess

import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.lfd.runtime.export_cpp import to_cpp
from sosdyn.lfd.runtime.export_python import to_python
from sosdyn.lfd.runtime.states import SPEED_KNEE, limit_speed

from export_support import import_source
from export_support import max_rel_error as rel

MAIN = """#include "model.hpp"
#include <cstdio>
int main() {
  double x[cdsp_model::N], g[cdsp_model::N], v[cdsp_model::N], w[cdsp_model::N];
  for (;;) {
    for (int i = 0; i < cdsp_model::N; ++i) if (std::scanf("%lf", &x[i]) != 1) return 0;
    for (int i = 0; i < cdsp_model::N; ++i) if (std::scanf("%lf", &g[i]) != 1) return 0;
    const bool ok = cdsp_model::predict(x, v, g) && cdsp_model::predict(x, w);
    for (int i = 0; i < cdsp_model::N; ++i) std::printf("%.17g ", v[i]);
    for (int i = 0; i < cdsp_model::N; ++i) std::printf("%.17g ", w[i]);
    std::printf("%d\\n", ok ? 1 : 0);
  }
}
"""


@pytest.fixture
def model(field_model):
    return field_model


def states_and_goals(model, count=200, seed=3):
    rng = np.random.default_rng(seed)
    X = model.goal_ + model.scale_ * rng.uniform(-2, 2, size=(count, model.dim_))
    G = model.goal_ + model.scale_ * rng.uniform(-0.5, 0.5, size=(count, model.dim_))
    return X, G


def moved(model, X, G):
    """The model with its goal moved to G: model.predict at the translated states."""
    return model.predict(X - G + model.goal_)


def test_predictor_and_python_export_with_a_moved_goal(model, tmp_path):
    X, G = states_and_goals(model)
    want = moved(model, X, G)
    np.testing.assert_allclose(np.array([model.field(x[None], g)[0] for x, g in zip(X, G)]), want, rtol=1e-12)
    step = model.predictor()
    assert rel(np.array([step(x, goal=g) for x, g in zip(X, G)]), want) < 1e-12
    gen = import_source(to_python(model), tmp_path / "gen_goal.py")
    assert rel(np.array([gen.predict(x, goal=g) for x, g in zip(X, G)]), want) < 1e-12
    assert rel(gen.predict(X), model.predict(X)) < 1e-12                # goal=None: the model's
    with pytest.raises(ValueError, match="goal"):
        gen.predict(X, goal=[1.0])


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_cpp_export_with_a_moved_goal_and_a_speed_limit(model, tmp_path):
    X, G = states_and_goals(model, 100)
    v_max = 0.5 * float(np.median(np.linalg.norm(model.predict(X), axis=1)))
    for name, limit in (("free", None), ("limited", v_max)):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "model.hpp").write_text(to_cpp(model, max_speed=limit))
        (folder / "main.cpp").write_text(MAIN)
        exe = folder / "main"
        subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe),
                        str(folder / "main.cpp")], check=True, capture_output=True, text=True)
        stdin = "\n".join(" ".join(repr(float(v)) for v in (*x, *g)) for x, g in zip(X, G))
        res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True)
        out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
        n = model.dim_
        assert (out[:, -1] == 1).all()
        assert rel(out[:, :n], limit_speed(moved(model, X, G), limit)) < 1e-12
        assert rel(out[:, n:2 * n], limit_speed(model.predict(X), limit)) < 1e-12
    assert np.linalg.norm(out[:, :n], axis=1).max() <= v_max * (1 + 1e-12)
    free = np.linalg.norm(moved(model, X, G), axis=1)
    assert (np.linalg.norm(out[:, :n], axis=1) < free * (1 - 1e-3)).sum() > 10       # the limit acts


def test_speed_limit_bounds_the_speed_and_keeps_directions(model, tmp_path):
    X, G = states_and_goals(model)
    free = moved(model, X, G)
    v_max = 0.5 * float(np.median(np.linalg.norm(free, axis=1)))
    step = model.predictor(max_speed=v_max)
    limited = np.array([step(x, goal=g) for x, g in zip(X, G)])
    speeds = np.linalg.norm(limited, axis=1)
    assert speeds.max() <= v_max * (1 + 1e-12)
    slow = np.linalg.norm(free, axis=1) <= SPEED_KNEE * v_max
    assert 0 < slow.sum() < len(X)
    np.testing.assert_allclose(limited[slow], free[slow], rtol=1e-12)              # factor 1 below the knee
    assert (speeds[~slow] < np.linalg.norm(free[~slow], axis=1)).all()
    cos = np.einsum("ij,ij->i", limited, free) / (speeds * np.linalg.norm(free, axis=1))
    assert cos.min() > 1 - 1e-12                                                    # same direction
    gen = import_source(to_python(model, max_speed=v_max), tmp_path / "gen_speed.py")
    assert rel(gen.predict(X, goal=G[0]), limit_speed(moved(model, X, G[0]), v_max)) < 1e-12
    for bad in (0, -1.0, np.inf, True, "1"):
        with pytest.raises(InputError, match="max_speed"):
            model.predictor(max_speed=bad)


def test_speed_limited_rollout_follows_the_same_path_to_the_goal(model):
    """Time reparametrisation: the limited rollout visits the free rollout's path, slower, and
    still reaches the goal (a longer duration)."""
    x0 = model.goal_ + model.scale_ * np.array([1.5, -1.0])
    free = model.rollout(x0, 80.0, dt=0.002)       # as long as the limited one: it covers the whole path
    speeds = np.linalg.norm(np.diff(free.pos, axis=0), axis=1) / 0.002
    v_max = 0.3 * speeds.max()
    slow = model.rollout(x0, 80.0, dt=0.01, max_speed=v_max)
    assert (np.linalg.norm(np.diff(slow.pos, axis=0), axis=1) / 0.01).max() <= v_max * 1.01
    assert np.linalg.norm(slow.pos[-1] - model.goal_) < 1e-2 * model.scale_
    # every point of the limited path lies on the free path (dense polyline distance)
    a, b = free.pos[:-1], free.pos[1:]
    def to_polyline(p):
        s = np.clip(np.einsum("ij,ij->i", p - a, b - a) / np.maximum(np.einsum("ij,ij->i", b - a, b - a), 1e-300), 0, 1)
        return np.linalg.norm(a + s[:, None] * (b - a) - p, axis=1).min()
    gap = max(to_polyline(p) for p in slow.pos[::100])
    assert gap < 1e-4 * model.scale_, gap
    with pytest.raises(InputError, match="max_speed"):
        model.rollout(x0, 1.0, max_speed=0)


def compiled(model, folder, max_speed):
    """The C++ export with MAIN, compiled in ``folder``; returns a function (X, G) -> the C++ output rows."""
    folder.mkdir()
    (folder / "model.hpp").write_text(to_cpp(model, max_speed=max_speed))
    (folder / "main.cpp").write_text(MAIN)
    exe = folder / "main"
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe), str(folder / "main.cpp")],
                   check=True, capture_output=True, text=True)

    def run(X, G):
        stdin = "\n".join(" ".join(repr(float(v)) for v in (*x, *g)) for x, g in zip(X, G))
        res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True)
        return np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    return run


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_the_speed_limited_field_far_away_is_not_zero_in_any_path(field_model, tmp_path):
    """From ~1e155 units away |xdot|^2 overflowed, min(1, v / inf) = 0, and every path returned a zero
    velocity off the goal (issue 35). Now: the predictor (model's goal and a moved one), the Python
    export (one state and batch), the C++ export and the rollout's field give the free direction at a
    speed between SPEED_KNEE v and v."""
    model = field_model
    if model.field_degree != 1 or model.warp_ is not None:
        pytest.skip("a cubic or warped field overflows float there (InputError), the limit has nothing to act on")
    v = 2.0
    X = model.goal_ + np.array([[1e155, -3e154], [-2e155, 4e155], [3e150, 1e149]])
    G = np.tile(model.goal_ + 1.0, (len(X), 1))
    free = moved(model, X, G)
    free = free / np.linalg.norm(free / 1e150, axis=1)[:, None] / 1e150        # the free directions
    step = model.predictor(max_speed=v)
    gen = import_source(to_python(model, max_speed=v), tmp_path / "gen_far.py")
    run = compiled(model, tmp_path / "cpp", v)(X, G)
    paths = {"predictor": np.array([step(x, goal=g) for x, g in zip(X, G)]),
             "python one state": np.array([gen.predict(x, goal=g) for x, g in zip(X, G)]),
             "python batch": np.array([gen.predict(X, goal=g)[i] for i, g in enumerate(G)]),
             "cpp": run[:, :model.dim_],
             "rollout field": limit_speed(np.array([model.field(x[None], g)[0] for x, g in zip(X, G)]), v)}
    assert (run[:, -1] == 1).all()
    for name, V in paths.items():
        speeds = np.linalg.norm(V, axis=1)
        assert np.all((speeds > SPEED_KNEE * v) & (speeds <= v * (1 + 1e-12))), (name, speeds)
        assert np.einsum("ij,ij->i", V, free).min() / speeds.max() > 1 - 1e-12, name
        assert rel(V, paths["predictor"]) < 1e-12, name

"""The speed floor (issue 36.5; sosdyn.lfd.fit.floor): sigma(x) = min(B, max(1, kappa |x - x*| / |f(x)|)), a
time change: the same paths, at least the certified rate, exports and files that carry it, a choice that
uses it only where the training reproductions would arrive late."""
import json
import shutil
import subprocess

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit.floor import ARRIVAL, BOOST, RATE_QUANTILES, fade, floor_choice, floored, relative_speeds
from sosdyn.lfd.fit.pipeline import with_floor
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.fileformat import _digest
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.model.reach import metric_matrix
from sosdyn.lfd.runtime.export_cpp import to_cpp
from sosdyn.lfd.runtime.export_python import to_python

from export_support import import_source, max_rel_error


def test_the_factor_by_hand():
    """|d| = 5: kappa 1 asks for speed 5 against |v| = 0.1 (capped at B = 10); kappa 0.01 asks for 0.05 < 0.1
    (no change); v = 0 away from the goal stays 0; at the goal sigma = 1."""
    D, V = np.array([[3.0, 4.0], [3.0, 4.0], [3.0, 4.0], [0.0, 0.0]]), np.array([[0.1, 0.0], [0.1, 0.0], [0, 0], [0, 0]])
    out = floored(D, V, np.array([[1.0], [0.01], [1.0], [1.0]]), 10.0)
    assert out.tolist() == [[1.0, 0.0], [0.1, 0.0], [0.0, 0.0], [0.0, 0.0]]
    assert floored(D[:1], V[:1], 30.0, 1e4)[0, 0] == pytest.approx(150.0)        # sigma = 30 * 5 / 0.1 = 1500
    assert floored(D[:1], V[:1], 30.0, 1e3)[0, 0] == pytest.approx(100.0)        # capped at 1000


def test_the_settle_zone_by_hand():
    """fade = 1 up to rho / 2, 0 from rho, 1/2 at 3 rho / 4 (the smoothstep's midpoint), continuous slope; a
    floor with a zone is the whole floor within rho / 2 and no floor beyond rho."""
    assert fade(np.array([0.0, 0.5, 0.75, 1.0, 3.0])).tolist() == [1.0, 1.0, 0.5, 0.0, 0.0]
    u = np.array([0.5, 1.0])
    assert np.abs((fade(u + 1e-7) - fade(u - 1e-7)) / 2e-7).max() < 1e-6          # C^1 at both ends
    D = np.array([[0.3, 0.4], [3.0, 4.0], [1.2, 1.6]])           # |d| = 0.5, 5, 2 against rho = 2
    V = np.full((3, 2), 0.01)
    out = floored(D, V, 1.0, 10.0, 2.0)
    assert out[0] == pytest.approx(floored(D[:1], V[:1], 1.0, 10.0)[0])          # within rho / 2: the floor
    assert out[1:].tolist() == V[1:].tolist()                                      # from rho on: none


def test_relative_speeds_leave_out_the_goal():
    X = np.array([[1.0, 0.0], [0.5, 0.0], [0.001, 0.0], [0.0, 0.0]])
    V = np.array([[-2.0, 0.0], [-1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    assert relative_speeds(X, V, np.zeros(2)).tolist() == [2.0, 2.0]              # |x| > 0.01 x diag 1


@pytest.fixture(scope="module")
def slow(linear_demos):
    """The linear demos' model and the same with a fixed floor kappa = 2/s."""
    plain = CDSP(n_components=3, warp="none", speed_floor="none").fit(linear_demos)
    return plain, CDSP(n_components=3, warp="none", speed_floor=2.0).fit(linear_demos)


def test_a_floor_changes_the_clock_not_the_path(slow, linear_demos):
    """From one start, the floored rollout's points lie on the plain one's path (nearest distances at the
    rollout's resolution) and it reaches the goal sooner; it speeds up where it binds only."""
    plain, fast = slow
    assert plain.floor_ is None and fast.floor_ == {"rate": 2.0, "boost": BOOST}
    x0 = linear_demos[0].pos[0]
    a, b = plain.rollout(x0, 12.0, dt=1e-3), fast.rollout(x0, 12.0, dt=1e-3)
    gap = np.sqrt(((b.pos[:, None, :] - a.pos[None, ::5, :]) ** 2).sum(-1)).min(axis=1)
    step = np.linalg.norm(np.diff(a.pos[::5], axis=0), axis=1).max()
    assert gap.max() <= step
    near = lambda r: np.flatnonzero(np.linalg.norm(r.pos - plain.goal_, axis=1) < 0.05)[0]     # noqa: E731
    assert near(b) < near(a)
    V, W = plain.predict(a.pos), fast.predict(a.pos)
    ratio = np.linalg.norm(W, axis=1) / np.linalg.norm(V, axis=1)
    assert ratio.min() >= 1 - 1e-12 and ratio.max() > 1.5


def test_a_floored_trajectory_approaches_the_goal_at_the_certified_rate(slow, linear_demos):
    """|z|_M along the floored rollout decays at least as e^{-gamma t / 2} (the theorem of the module):
    no warp, constant metric, so u = z."""
    _, fast = slow
    M = metric_matrix(fast)
    run = fast.rollout(linear_demos[1].pos[0], 6.0, dt=1e-3)
    Z = (run.pos - fast.goal_) / fast.scale_
    d = np.sqrt(np.einsum("ti,ij,tj->t", Z, M, Z))
    assert np.all(d <= d[0] * np.exp(-fast.gamma * run.t / 2) * (1 + 1e-3) + 1e-12)


def test_the_choice_speeds_up_a_crawling_field_only():
    """Demos reaching the goal in 1 s; a field xdot = -0.5 x takes 9 s to get within 1 %: floored. A field
    xdot = -10 x arrives in time: no floor."""
    t = np.linspace(0, 1, 101)
    demos = Demonstrations([Demonstration.from_positions(t, np.outer(np.cos(np.pi * t / 2), d))
                            for d in ([1.0, 0.0], [0.0, 1.0], [0.7, 0.7])], "arc", "m")
    goal = np.zeros(2)
    rate, worst = floor_choice(lambda X: -0.5 * X, goal, demos)
    assert worst["none"] == np.inf and rate is not None          # beyond ARRIVAL: overdue
    chosen = next(name for name, k in zip(worst, [0.0, *np.quantile(
        relative_speeds(*demos.stacked(), goal), (0.25, 0.5, 0.75, 0.9))]) if k == rate)
    assert worst[chosen] <= ARRIVAL and all(worst[n] > ARRIVAL for n in list(worst)[:list(worst).index(chosen)])
    assert floor_choice(lambda X: -10.0 * X, goal, demos)[0] is None


def test_with_floor_settings(linear_demos):
    fitted = CDSP(n_components=3, warp="none", speed_floor="none").fit(linear_demos)
    assert with_floor(fitted, linear_demos, 3.5).floor_ == {"rate": 3.5, "boost": BOOST}
    assert with_floor(fitted, linear_demos, "none").floor_ is None
    with_floor(fitted, linear_demos, "auto")
    arrivals = fitted.floor_arrivals_              # "none" first; the others only when it is too slow
    assert "none" in arrivals and (arrivals["none"] <= ARRIVAL) == (fitted.floor_ is None)
    assert len(arrivals) == (1 if fitted.floor_ is None else 1 + len(RATE_QUANTILES))


@pytest.mark.parametrize("bad", [0, -1.0, "fast", True, float("nan")])
def test_a_bad_floor_setting_is_refused(bad, linear_demos):
    with pytest.raises(InputError, match="speed_floor"):
        CDSP(speed_floor=bad).fit(linear_demos)


@pytest.mark.parametrize("radius", [None, 1.2])
def test_predictor_and_exports_carry_the_floor(slow, tmp_path, radius):
    """The same numbers in the model, the predictor and both exports, with the floor everywhere or within
    a settle zone of radius 1.2 scales (the states reach 2.8 scales: inside, in the fade, and beyond)."""
    _, fast = slow
    if radius is not None:
        fast.save(tmp_path / "fast.json")
        fast = load_model(tmp_path / "fast.json")
        fast.floor_ = dict(fast.floor_, radius=radius * fast.scale_)
        fast.save(tmp_path / "zone.json")                   # the zone survives the file
        assert load_model(tmp_path / "zone.json").floor_ == fast.floor_
    X = fast.goal_ + fast.scale_ * np.random.default_rng(3).uniform(-2, 2, (400, 2))
    V = fast.predict(X)
    gen, step = import_source(to_python(fast), tmp_path / "floor.py"), fast.predictor()
    assert max_rel_error(gen.predict(X), V) < 1e-12
    assert max_rel_error(np.array([step(x) for x in X]), V) < 1e-12
    assert all(np.array_equal(gen.predict(x), step(x)) for x in X[:50])
    if shutil.which("g++") is None:
        return
    main = ('#include "model.hpp"\n#include <cstdio>\nint main() { double x[2], v[2];\n'
            '  while (std::scanf("%lf %lf", &x[0], &x[1]) == 2) { cdsp_model::predict(x, v);\n'
            '    std::printf("%.17g %.17g\\n", v[0], v[1]); } }\n')
    (tmp_path / "model.hpp").write_text(to_cpp(fast))
    (tmp_path / "main.cpp").write_text(main)
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(tmp_path / "main"),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    res = subprocess.run([str(tmp_path / "main")], input="\n".join(f"{float(a)!r} {float(b)!r}" for a, b in X),
                         capture_output=True, text=True, check=True)
    assert max_rel_error(np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()]), V) < 1e-12


def _write(data, path):
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    path.write_text(json.dumps(data))
    return path


def test_the_floor_in_a_model_file(slow, tmp_path):
    _, fast = slow
    fast.save(tmp_path / "m.json")
    data = json.loads((tmp_path / "m.json").read_text())
    assert data["state"]["floor_"] == {"rate": 2.0, "boost": BOOST}
    assert load_model(tmp_path / "m.json").floor_ == fast.floor_
    old = json.loads(json.dumps(data))
    del old["state"]["floor_"]                      # a file older than the floor: none
    del old["params"]["speed_floor"]
    assert load_model(_write(old, tmp_path / "old.json")).floor_ is None
    for bad, match in (({"rate": 2.0}, "optionally"), ({"rate": -1.0, "boost": 10.0}, "rate must be a positive"),
                       ({"rate": 1.0, "boost": 0.5}, "boost must be >= 1"),
                       ({"rate": 1.0, "boost": 2.0, "radius": 0.0}, "radius must be a positive"),
                       ({"rate": 1.0, "boost": 2.0, "radius": 1.0, "zone": 1}, "optionally")):
        data["state"]["floor_"] = bad
        with pytest.raises(ModelFileError, match=match):
            load_model(_write(data, tmp_path / "bad.json"))

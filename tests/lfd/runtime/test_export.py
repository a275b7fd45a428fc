"""Generated evaluators (sosdyn.lfd.runtime.export_python, export_cpp) compute what CDSP.predict computes."""
import re
import shutil
import subprocess

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sosdyn.errors import InputError, NotFittedError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit.gmm import with_bound
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.runtime.export_cpp import to_cpp
from sosdyn.lfd.runtime.export_python import to_python

from export_support import import_source, max_rel_error

TOL = 1e-9


@pytest.fixture
def model(field_model):
    """The conftest's linear / cubic / warped models (fitted once per session)."""
    return field_model


def box_states(model, count, seed=0):
    """``count`` states uniform in twice the data box (about the goal, half-width 2 scale)."""
    rng = np.random.default_rng(seed)
    return model.goal_ + model.scale_ * rng.uniform(-2, 2, size=(count, model.dim_))


def test_python_export_matches_predict(model, tmp_path):
    source = to_python(model)
    assert not re.search(r"^\s*(import|from)\s+sosdyn", source, re.MULTILINE)
    gen = import_source(source, tmp_path / "gen.py")
    X = box_states(model, 10_000)
    err = max_rel_error(gen.predict(X), model.predict(X))
    assert err < TOL, err
    x = X[7]
    np.testing.assert_allclose(gen.predict(x), model.predict(x)[0], rtol=TOL)
    assert gen.predict(x).shape == (model.dim_,)


@pytest.mark.parametrize("tempered", [True, False])
def test_python_export_far_from_data_uses_the_far_weights(tmp_path, linear_demos, tempered):
    """Where the quadratic forms overflow: one-hot on the nearest component without a gating bound,
    the exact tempered softmax with one (both the fallback branch)."""
    model = CDSP(n_components=3, warp="none", gating="tempered").fit(linear_demos)
    if not tempered:
        model.mixture_ = with_bound(model.mixture_, None)
    gen = import_source(to_python(model), tmp_path / "far.py")
    far = model.goal_ + model.scale_ * np.array([[1e156, 3e155], [-2e157, 1e150], [5e155, -5e155]])
    Z = (far - model.goal_) / model.scale_
    H = model.mixture_.responsibilities(Z)
    assert (set(np.unique(H)) == {0.0, 1.0}) != tempered      # the fallback branch is the one tested
    np.testing.assert_allclose(gen.predict(far), model.predict(far), rtol=TOL)
    np.testing.assert_allclose(gen.predict(far[0]), model.predict(far)[0], rtol=TOL)   # one state
    with pytest.raises(ValueError, match="NaN or inf"):
        gen.predict([np.nan, 0.0])
    with pytest.raises(ValueError, match="shape"):
        gen.predict(np.zeros((2, 3)))


def test_unfitted_model_and_unknown_target():
    with pytest.raises(NotFittedError, match="fitted"):
        to_python(CDSP())
    with pytest.raises(ValueError, match="python, cpp"):
        CDSP().export("rust")


MAIN = """#include "model.hpp"
#include <cstdio>
int main() {
  double x[cdsp_model::N], v[cdsp_model::N];
  for (;;) {
    for (int i = 0; i < cdsp_model::N; ++i) if (std::scanf("%lf", &x[i]) != 1) return 0;
    const bool ok = cdsp_model::predict(x, v);
    for (int i = 0; i < cdsp_model::N; ++i) std::printf("%.17g ", v[i]);
    std::printf("%d\\n", ok ? 1 : 0);
  }
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_cpp_export_matches_predict(model, tmp_path):
    (tmp_path / "model.hpp").write_text(to_cpp(model))
    (tmp_path / "main.cpp").write_text(MAIN)
    exe = tmp_path / "main"
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    X = box_states(model, 1000, seed=1)
    far = model.goal_ + model.scale_ * np.array([[1e156, 3e155]])   # finite for the linear field only
    X = np.vstack([X, far]) if model.field_degree == 1 else X
    stdin = "\n".join(" ".join(repr(float(v)) for v in row) for row in X)
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True)
    out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    assert out.shape == (len(X), model.dim_ + 1)
    assert (out[:, -1] == 1).all()
    err = max_rel_error(out[:, :-1], model.predict(X))
    assert err < TOL, err
    bad = subprocess.run([str(exe)], input="nan 0\n", capture_output=True, text=True, check=True)
    assert bad.stdout.split()[-1] == "0"


def test_python_export_refuses_an_overflowing_state_like_predict(model, tmp_path):
    """Where the field overflows float (z^3 at |z| ~ 1e120), both refuse the state."""
    if model.field_degree == 1:
        pytest.skip("a linear field does not overflow at |z| ~ 1e120")
    gen = import_source(to_python(model), tmp_path / "overflow.py")
    far = model.goal_ + model.scale_ * np.array([[1e120, 1e120]])
    with pytest.raises(InputError, match="overflows float"):
        model.predict(far)
    with pytest.raises(ValueError, match="overflows float"):
        gen.predict(far)


def test_python_export_of_one_state_is_the_predictors_arithmetic(model, tmp_path):
    """One finite state (and a moved goal): the generated module runs the predictor's own functions,
    so the numbers are the predictor's bit for bit (the batch path agrees to rounding only)."""
    gen, step = import_source(to_python(model), tmp_path / "one.py"), model.predictor()
    X = box_states(model, 200, seed=4)
    assert all(np.array_equal(gen.predict(x), step(x)) for x in X)
    g = model.goal_ + 0.1 * model.scale_
    assert all(np.array_equal(gen.predict(x, goal=g), step(x, goal=g)) for x in X[:20])


@pytest.fixture(scope="module")
def twisted_3d():
    """A 3-D model through a twist in a tilted plane (and two bumps): spirals of xdot = A x whose plane is
    not a coordinate plane, with a slow third coordinate."""
    Q = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))[0]
    A = Q @ np.array([[-0.5, 3.0, 0.0], [-3.0, -0.5, 0.0], [0.0, 0.0, -1.0]]) @ Q.T
    t = np.linspace(0, 8, 200)
    demos = [Demonstration(t, sol.y.T, sol.y.T @ A.T, f"d{k}") for k, x0 in enumerate(
        ([1.0, 0.2, 0.3], [-0.5, 0.9, -0.2], [0.3, -1.0, 0.5])) for sol in [solve_ivp(
            lambda _, x: A @ x, (0, 8), x0, t_eval=t, rtol=1e-10, atol=1e-12)]]
    m = CDSP(n_components=2, warp={"n_maps": 2, "twist": 3.0}, corrective_rounds=0, random_state=0,
             verify_samples=1000).fit(Demonstrations(demos, "spiral3d", "m"))
    assert m.certified_ and "twist" in m.warp_ and m.dim_ == 3
    return m


def test_exports_of_a_3d_twisted_model_match_predict(twisted_3d, tmp_path):
    m = twisted_3d
    X = box_states(m, 500, seed=2)
    gen = import_source(to_python(m), tmp_path / "twist3d.py")
    assert max_rel_error(gen.predict(X), m.predict(X)) < TOL
    assert all(np.array_equal(gen.predict(x), m.predictor()(x)) for x in X[:50])
    assert max_rel_error(np.array([m.predictor()(x) for x in X]), m.predict(X)) < TOL
    if shutil.which("g++") is None:
        return
    (tmp_path / "model.hpp").write_text(to_cpp(m))
    (tmp_path / "main.cpp").write_text(MAIN)
    subprocess.run(["g++", "-std=c++17", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(tmp_path / "main"),
                    str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
    stdin = "\n".join(" ".join(repr(float(v)) for v in row) for row in X)
    res = subprocess.run([str(tmp_path / "main")], input=stdin, capture_output=True, text=True, check=True)
    out = np.array([[float(v) for v in line.split()] for line in res.stdout.splitlines()])
    assert (out[:, -1] == 1).all() and max_rel_error(out[:, :-1], m.predict(X)) < TOL

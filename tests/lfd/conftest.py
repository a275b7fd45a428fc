"""Fixtures for the demonstration, rollout and learner tests."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sosdyn.errors import SosdynError
from sosdyn.lfd.data import lasa
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations

# A linear system that contracts in a non-identity metric only: eigenvalues -1, -1 but
# A + A^T has eigenvalue +2, so the quadratic Lyapunov V = |x|^2 (SEDS) cannot certify it.
A_TRUE = np.array([[-1.0, 4.0], [0.0, -1.0]])
GOAL = np.array([2.0, -1.0])


@pytest.fixture(scope="session")
def leaf():
    """The LASA Leaf_1 demonstrations; the test is skipped when the LASA data is not installed."""
    try:
        lasa.lasa_dir()
    except SosdynError as exc:
        pytest.skip(str(exc))
    return lasa.load_lasa("Leaf_1")


@pytest.fixture(scope="session")
def linear_system():
    """(A, goal): xdot = A (x - goal), contracting in a learned metric only (see A_TRUE)."""
    return A_TRUE.copy(), GOAL.copy()


@pytest.fixture(scope="session")
def linear_demos():
    """Four exact demonstrations of the linear system, 200 samples over 6 s each."""
    starts, T, tf = ((-8, 3), (6, 4), (-5, -6), (7, -5)), 200, 6.0
    t = np.linspace(0, tf, T)
    demos = []
    for i, s in enumerate(starts):
        z0 = np.asarray(s, dtype=float)
        sol = solve_ivp(lambda _, z: A_TRUE @ z, (0, tf), z0, t_eval=t, rtol=1e-10, atol=1e-12)
        z = sol.y.T
        demos.append(Demonstration(t, z + GOAL, z @ A_TRUE.T, source=f"demo{i}"))
    return Demonstrations(demos, name="linear", units="m")


def _line_demo(start, goal=(0.0, 0.0), T=50, duration=2.0, source=""):
    """A straight motion start -> goal with a smooth (cubic) time law and its exact velocity."""
    t = np.linspace(0.0, duration, T)
    s = 3 * (t / duration) ** 2 - 2 * (t / duration) ** 3
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    pos = start + s[:, None] * (goal - start)
    vel = (6 * t / duration**2 - 6 * t**2 / duration**3)[:, None] * (goal - start)
    return Demonstration(t, pos, vel, source)


@pytest.fixture
def make_line_demo():
    """line_demo(start, goal=(0, 0), T=50, duration=2.0, source=""): a straight cubic-time motion."""
    return _line_demo


@pytest.fixture
def demos():
    """Three straight 2-D motions to the origin, units mm."""
    return Demonstrations([_line_demo((10, 5)), _line_demo((8, -4)), _line_demo((-6, 9))], "lines", "mm")


@pytest.fixture(scope="session", params=[1, 3, "warped", "twisted"], ids=["linear", "cubic", "warped", "twisted"])
def field_model(request, linear_demos):
    """CDSP models of the linear demos whose fields the evaluator and export tests compare with
    predict: linear and cubic sub-systems without a warp, and the linear one with a fixed warp,
    without and with a twist about the goal after its bumps."""
    if request.param in ("warped", "twisted"):  # 20 bumps (the linear demos' spirals are not radial)
        m = CDSP(n_components=3, warp={"n_maps": 20, "twist": 3.0 if request.param == "twisted" else 0.0}
                 ).fit(linear_demos)
        assert len(m.warp_["sigmas"]) >= 10      # measured 19 (the fit stops when no bump helps)
        assert ("twist" in m.warp_) == (request.param == "twisted")
        return m
    return CDSP(n_components=3, field_degree=request.param, warp="none").fit(linear_demos)


@pytest.fixture(scope="session")
def hook_demos():
    """Three demonstrations of a hook: out to 3.5x the start's distance from the goal (the origin),
    around it by 270 degrees, then in; no constant metric sees the distance decrease."""
    t = np.linspace(0, 4, 200)
    sm = 3 * (t / 4) ** 2 - 2 * (t / 4) ** 3
    demos = []
    for k, (r0, th0) in enumerate(((1.0, 0.6), (1.1, 0.75), (0.9, 0.5))):
        r, th = r0 * (1 + 2.5 * np.sin(np.pi * sm)) * (1 - sm), th0 + 1.5 * np.pi * sm
        demos.append(Demonstration.from_positions(t, np.column_stack([r * np.cos(th), r * np.sin(th)]), f"hook {k}"))
    return Demonstrations(demos, "hook")


@pytest.fixture(scope="session")
def second_order_system():
    """(A, B, goal, demos): four exact demos of the certified linear second-order system
    x'' = A (x - g) + B x' (eigenvalues with real parts <= -1), 401 samples over 10 s each."""
    A, B, goal = np.array([[-4.0, 1.0], [0.0, -3.0]]), np.array([[-3.0, 0.5], [-0.5, -2.5]]), np.array([5.0, -2.0])
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 10.0, 401)
    out = []
    for _ in range(4):
        y0 = np.concatenate([rng.uniform(-10, 10, 2), rng.uniform(-20, 20, 2)])
        sol = solve_ivp(lambda _, y: np.concatenate([y[2:], A @ y[:2] + B @ y[2:]]), (0, 10), y0,
                        t_eval=t, rtol=1e-10, atol=1e-12)
        out.append(Demonstration.from_positions(t, sol.y[:2].T + goal))
    return A, B, goal, Demonstrations(out, name="linear-2nd")

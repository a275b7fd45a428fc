"""CDSP.rollout has the same relative accuracy in any units (issue 23, item 4): the integrator's
absolute tolerance is relative to the data's scale (ATOL_REL * scale_), not fixed in data units."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.model.cdsp import CDSP

UNITS = {"m": 1.0, "mm": 1e3, "nm": 1e9, "Gm": 1e-9}


@pytest.fixture(scope="module")
def rollout_errors(linear_demos):
    """Per units: max_t |x(t) - x_ref(t)| / scale_ of CDSP.rollout from the first demo's start, the
    reference integrated in z = (x - goal) / scale_ with DOP853 at rtol 1e-12, atol 1e-14."""
    out = {}
    for units, c in UNITS.items():
        demos = Demonstrations([Demonstration(d.t, d.pos * c, d.vel * c) for d in linear_demos], "lin", units)
        m = CDSP(n_components=1, warp="none").fit(demos)
        x0 = demos[0].pos[0]
        traj = m.rollout(x0, 6.0, dt=0.01)
        ref = solve_ivp(lambda _, z: m.field(m.goal_ + m.scale_ * z[None], m.goal_)[0] / m.scale_, (0.0, 6.0),
                        (x0 - m.goal_) / m.scale_, method="DOP853", t_eval=traj.t, rtol=1e-12, atol=1e-14).y.T
        out[units] = float(np.abs((traj.pos - m.goal_) / m.scale_ - ref).max())
    return out


def test_metres_millimetres_nanometres_give_the_same_relative_accuracy(rollout_errors):
    """Measured 6.28e-7 of the data's scale in all four (with the former fixed atol = 1e-8 data units:
    the same in m, mm and nm, 1.2e-2 in Gm, where the numbers are 1e-9 times those in m)."""
    errs = np.array(list(rollout_errors.values()))
    assert errs.max() < 1e-5, rollout_errors
    assert errs.max() < 2 * errs.min(), rollout_errors

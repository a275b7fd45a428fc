"""The pose protocol's copy at the nearest start: which recorded demo a robot given only the start replays."""
import numpy as np

from sosdyn.evaluation.poses import nearest_start, turned
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations

Q0 = np.array([1.0, 0.0, 0.0, 0.0])


def _demo(start, quat):
    t = np.linspace(0.0, 1.0, 5)
    pos = np.outer(1.0 - t, start)
    return PoseDemonstration(t, pos, np.tile(quat, (5, 1)), "synthetic")


def test_nearest_start_weighs_a_diagonal_as_a_half_turn():
    """Start at the origin, identity orientation, diag 10: a demo starting 3 away and turned 10 deg scores
    0.3 + 0.056; one at the same place turned 120 deg scores 0.667; one 8 away unturned 0.8."""
    demos = PoseDemonstrations([_demo([0.0, 0.0, 0.0], turned(Q0, 120.0, [0, 0, 1])),
                                _demo([3.0, 0.0, 0.0], turned(Q0, 10.0, [1, 0, 0])),
                                _demo([0.0, 8.0, 0.0], Q0)], "synthetic", "m")
    assert nearest_start(demos, np.zeros(3), Q0, 10.0) == 1
    assert nearest_start(demos, np.zeros(3), turned(Q0, 120.0, [0, 0, 1]), 10.0) == 0
    assert nearest_start(demos, np.array([0.0, 8.0, 0.0]), Q0, 10.0) == 2

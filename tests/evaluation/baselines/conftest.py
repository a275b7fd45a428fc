"""Shared data for the baseline tests: synthetic demonstrations and (when installed) LASA."""

import numpy as np
import pytest

from sosdyn.errors import SosdynError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.lasa import load_lasa

GOAL = np.array([1.0, 2.0])   # where straight_demos end


@pytest.fixture(scope="session")
def straight_demos():
    """Constant-speed straight lines into g that stop abruptly, all arriving from the upper
    left: the GMR of this data keeps moving through the goal (an unstable nominal field)."""
    t = np.linspace(0.0, 5.0, 101)
    demos = []
    for angle in np.deg2rad([100.0, 120.0, 140.0, 160.0]):
        x0 = GOAL + 5.0 * np.array([np.cos(angle), np.sin(angle)])
        velocity = np.tile((GOAL - x0) / 5.0, (len(t), 1))
        velocity[-1] = 0.0
        demos.append(Demonstration(t, x0 + t[:, None] * velocity[0], velocity))
    return Demonstrations(demos, "straight", "m")


@pytest.fixture(scope="session")
def leaf_1():
    try:
        return load_lasa("Leaf_1")
    except SosdynError as exc:
        pytest.skip(f"LASA data unavailable: {exc}")

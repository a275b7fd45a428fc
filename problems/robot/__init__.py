"""The robot experiment: CDSP and a baseline drive a simulated Franka Panda (pybullet) from real
demonstrations, with pushes and a moving goal (``python -m problems robot``; :mod:`.run`).

Needs the ``[robot]`` extra (pybullet); without it ``main`` raises InputError saying so. The
library itself never imports the simulator.
"""
from importlib.util import find_spec

from sosdyn.errors import InputError

if find_spec("pybullet") is None:
    def main(argv=None):
        raise InputError("the robot experiment needs pybullet, which is not installed. "
                         "Try: pip install -e '.[robot]' (or make venv, which installs [all]).")
else:
    from .run import main

__all__ = ["main"]

"""The robot experiment: CDSP and a baseline drive a simulated Franka Panda (pybullet) from real
demonstrations, with pushes and a moving goal (``python -m problems robot``; :mod:`.run`).

Needs the ``[robot]`` extra (pybullet). The library itself never imports the simulator.
"""
from .run import main

__all__ = ["main"]

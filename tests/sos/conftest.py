"""Fixtures shared by the SOS tests: forged solutions, random programs, a dense program, no solver."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import Solution, backends
from sosdyn.sos.conic import positions


def _forged(prog, values, solver="forged"):
    """A Solution claiming status optimal for hand-set values [(psd block or variable, array)]."""
    data = prog.compile()
    x = np.zeros(data.n)
    for item, v in values:
        x[positions(data.ids, item.ids)] = v
    return Solution(prog, data, "optimal", x, solver, "direct", {})


def _random_program(seed, kind):
    """maximize g: p - g SOS (``global``) or p - g >= 0 on the unit disk (``disk``).

    p = x^4 + y^4 + random lower-degree terms (bounded below). Returns (prog, g, p, disk).
    """
    rng = np.random.default_rng(seed)
    x, y = sd.variables("x y")
    p = x**4 + y**4
    for (i, j) in [(1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (2, 1), (1, 2), (3, 0)]:
        p = p + float(rng.normal()) * x**i * y**j
    prog = sd.SOSProgram(f"random {kind} {seed}")
    g = prog.new_var()
    disk = 1 - x**2 - y**2
    if kind == "global":
        prog.add_sos(p - g)
    else:
        prog.add_nonneg_on(p - g, ineqs=[disk], degree=4)
    prog.maximize(g)
    return prog, g, p, disk


def _dense_program(degree, **kw):
    """max g s.t. (1 + x^2 + y^2)^(degree/2) - g SOS: a dense Gram basis, answer g = 1."""
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos((1 + x**2 + y**2) ** (degree // 2) - g, **kw)
    prog.maximize(g)
    return prog, g


@pytest.fixture(scope="session")
def forged():
    """forged(prog, [(item, values)], solver="forged") -> a Solution claiming "optimal"."""
    return _forged


@pytest.fixture(scope="session")
def random_program():
    """random_program(seed, "global" | "disk") -> (prog, g, p, disk)."""
    return _random_program


@pytest.fixture(scope="session")
def dense_program():
    """dense_program(degree, **add_sos_kw) -> (prog, g) with a dense Gram basis, answer g = 1."""
    return _dense_program


@pytest.fixture
def no_solver(monkeypatch):
    def refuse(*args):
        raise AssertionError("the solver was called")
    monkeypatch.setattr(backends, "_clarabel", refuse)
    monkeypatch.setattr(backends, "_cvxpy", refuse)


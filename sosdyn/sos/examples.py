"""Textbook SOS problems with known answers, stated once (../shared/reference/sos-known-answers.md).

The known-answer tests (tests/sos/test_examples.py) assert their answers and
``make bench-sos`` times them (problems/bench/sos_problems.py).
"""
from __future__ import annotations

import numpy as np

from ..poly import PolyMatrix, jacobian, variables
from .program import SOSProgram


def chebyshev(degree: int = 8):
    """max the leading coefficient of p (deg 8) with |p| <= 1 on [-1, 1] (Putinar); answer 128.

    Returns (program, p).
    """
    (x,) = variables("x")
    prog = SOSProgram("chebyshev")
    p = prog.new_poly([x], degree)
    box = [1 - x**2]
    prog.add_nonneg_on(1 - p, ineqs=box, degree=degree)
    prog.add_nonneg_on(1 + p, ineqs=box, degree=degree)
    prog.maximize(p.coeff(x**degree))
    return prog, p


def probability_bound():
    """min a + b + 1.25c, q = a + bx + cx^2 >= 0 on [0, 5], q >= 1 on [4, 5]; answer 1/37.

    Returns (program, (a, b, c)).
    """
    (x,) = variables("x")
    prog = SOSProgram("probability bound")
    a, b, c = (prog.new_var() for _ in range(3))
    q = a + b * x + c * x**2
    prog.add_nonneg_on(q, ineqs=[x * (5 - x)], degree=2)
    prog.add_nonneg_on(q - 1, ineqs=[(x - 4) * (5 - x)], degree=2)
    prog.minimize(a + b + 1.25 * c)
    return prog, (a, b, c)


def disc_minimum():
    """max g with x - g >= 0 on the unit disc x^2 + y^2 <= 1 (Putinar, degree 2); answer -1,
    attained at (-1, 0), certificate x + 1 = (1 + x)^2/2 + y^2/2 + (1 - x^2 - y^2)/2.

    Returns (program, g, constraint).
    """
    x, y = variables("x y")
    prog = SOSProgram("disc minimum")
    g = prog.new_var(name="g")
    con = prog.add_nonneg_on(x - g, ineqs=[1 - x**2 - y**2], degree=2)
    prog.maximize(g)
    return prog, g, con


def moore_greitzer_field(x1, x2):
    return [-x2 - 1.5 * x1**2 - 0.5 * x1**3, 3 * x1 - x2]


def moore_greitzer(beta: float, delta: float = 1e-3):
    """A degree-4 contraction metric for the Moore-Greitzer model at rate beta.

    M - delta I and -(M J + J^T M + Mdot + beta M) - delta I SOS matrices: feasible at
    beta = 0.77, infeasible at 0.85. Returns the program.
    """
    x1, x2 = variables("x1 x2")
    f = moore_greitzer_field(x1, x2)
    J = jacobian(f, [x1, x2])
    prog = SOSProgram("Moore-Greitzer")
    m11, m12, m22 = (prog.new_poly([x1, x2], 4) for _ in range(3))
    M = PolyMatrix([[m11, m12], [m12, m22]])
    Mdot = M.directional_derivative(f, [x1, x2])
    prog.add_sos_matrix(M - delta * PolyMatrix.identity(2))
    prog.add_sos_matrix(-(M @ J + J.T @ M + Mdot + beta * M) - delta * PolyMatrix.identity(2))
    return prog


def floudas(degree: int):
    """Floudas & Pardalos 4.10: min -x1 - x2 on a box with two quartic constraints.

    The minimum is -5.5080133 (x = (2.3295, 3.1785), :func:`floudas_minimum`); Putinar degree
    6 gives -6.6667, degree 8 the minimum. Returns (program, g) for "maximize g with
    -x1 - x2 - g >= 0 there".
    """
    x1, x2 = variables("x1 x2")
    prog = SOSProgram(f"floudas {degree}")
    g = prog.new_var()
    ineqs = [2 * x1**4 - 8 * x1**3 + 8 * x1**2 + 2 - x2,
             4 * x1**4 - 32 * x1**3 + 88 * x1**2 - 96 * x1 + 36 - x2,
             x1, 3 - x1, x2, 4 - x2]
    prog.add_nonneg_on(-x1 - x2 - g, ineqs=ineqs, degree=degree)
    prog.maximize(g)
    return prog, g


def floudas_minimum() -> float:
    """The true minimum of :func:`floudas`, by a fine grid over x1 (x2 = min of the two quartics and 4)."""
    x1 = np.linspace(0, 3, 300_001)
    u = 2 * x1**4 - 8 * x1**3 + 8 * x1**2 + 2
    v = 4 * x1**4 - 32 * x1**3 + 88 * x1**2 - 96 * x1 + 36
    x2 = np.minimum(np.minimum(u, v), 4.0)
    return float(np.min(np.where(x2 >= 0, -x1 - x2, np.inf)))


def matrix_program():
    """maximize t with [[x^2+2, x^2], [x^2, x^2+2]] - t I an SOS matrix: the supremum is 2.

    Returns (program, t, constraint).
    """
    (x,) = variables("x")
    prog = SOSProgram("matrix")
    t = prog.new_var()
    P = PolyMatrix([[x**2 + 2, x**2], [x**2, x**2 + 2]])
    con = prog.add_sos_matrix(P - t * PolyMatrix.identity(2))
    prog.maximize(t)
    return prog, t, con

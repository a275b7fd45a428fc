"""Textbook SOS problems stated once (../shared/reference/sos-known-answers.md).

The known-answer tests (tests/sos/test_known_answers.py) assert their answers and
``make bench-sos`` times them.
"""
from __future__ import annotations

import sosdyn as sd
from sosdyn.poly import PolyMatrix, jacobian


def chebyshev(degree: int = 8):
    """max the leading coefficient of p (deg 8) with |p| <= 1 on [-1, 1] (Putinar); answer 128.

    Returns (program, p).
    """
    (x,) = sd.variables("x")
    prog = sd.SOSProgram("chebyshev")
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
    (x,) = sd.variables("x")
    prog = sd.SOSProgram("probability bound")
    a, b, c = (prog.new_var() for _ in range(3))
    q = a + b * x + c * x**2
    prog.add_nonneg_on(q, ineqs=[x * (5 - x)], degree=2)
    prog.add_nonneg_on(q - 1, ineqs=[(x - 4) * (5 - x)], degree=2)
    prog.minimize(a + b + 1.25 * c)
    return prog, (a, b, c)


def moore_greitzer_field(x1, x2):
    return [-x2 - 1.5 * x1**2 - 0.5 * x1**3, 3 * x1 - x2]


def moore_greitzer(beta: float, delta: float = 1e-3):
    """A degree-4 contraction metric for the Moore-Greitzer model at rate beta.

    M - delta I and -(M J + J^T M + Mdot + beta M) - delta I SOS matrices: feasible at
    beta = 0.77, infeasible at 0.85. Returns the program.
    """
    x1, x2 = sd.variables("x1 x2")
    f = moore_greitzer_field(x1, x2)
    J = jacobian(f, [x1, x2])
    prog = sd.SOSProgram("Moore-Greitzer")
    m11, m12, m22 = (prog.new_poly([x1, x2], 4) for _ in range(3))
    M = PolyMatrix([[m11, m12], [m12, m22]])
    Mdot = M.directional_derivative(f, [x1, x2])
    prog.add_sos_matrix(M - delta * PolyMatrix.identity(2))
    prog.add_sos_matrix(-(M @ J + J.T @ M + Mdot + beta * M) - delta * PolyMatrix.identity(2))
    return prog

"""The cvxpy lowering (issue 15, item 5): each Gram block enters as one PSD constraint on its
svec expression, with no equality rows Q = svec^-1(x) (whose symmetric duplicates made CVXOPT
fail every problem with "Rank(A) < p"). The known-answer suite through cvxpy with CLARABEL,
SCS (tight tolerances) and CVXOPT; MOSEK where it is installed and licensed.

Known answers: x^4 - 3x^2 + 2 >= -1/4 (at +-sqrt(3/2)); six-hump camel -1.0316284535;
Chebyshev T_8 leading coefficient 128; the probability bound 1/37; max t with
[[x^2+2, x^2], [x^2, x^2+2]] - tI SOS: 2 (eigenvalues x^2 + 2 +- x^2 >= 2); min x on the unit
disc -1; (x^2 + y^2 + 1) * Motzkin >= 0 (zeros at (+-1, +-1)); x^2 + x + 1 - g SDSOS: 3/4.
"""
import pytest

import sosdyn as sd
from sosdyn.sos import examples

SETTINGS = {"CLARABEL": {}, "CVXOPT": {}, "MOSEK": {},
            "SCS": {"eps_abs": 1e-9, "eps_rel": 1e-9, "max_iters": 200000}}


def bound(p, **kw):
    prog = sd.SOSProgram()
    g = prog.new_var(name="g")
    prog.add_sos(p - g, **kw)
    prog.maximize(g)
    return prog


def disc():
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_nonneg_on(x - g, ineqs=[1 - x**2 - y**2], degree=2)
    prog.maximize(g)
    return prog


def _x():
    return sd.variables("x")[0]


def _xy():
    return sd.variables("x y")


CASES = {
    "double well": (lambda: bound(_x()**4 - 3 * _x()**2 + 2), -0.25),
    "six-hump camel": (lambda: bound(4 * _xy()[0]**2 - 2.1 * _xy()[0]**4 + _xy()[0]**6 / 3 + _xy()[0] * _xy()[1]
                                     - 4 * _xy()[1]**2 + 4 * _xy()[1]**4), -1.0316284535),
    "chebyshev": (lambda: examples.chebyshev()[0], 128.0),
    "probability": (lambda: examples.probability_bound()[0], 1 / 37),
    "matrix": (lambda: examples.matrix_program()[0], 2.0),
    "disc": (disc, -1.0),
    "motzkin x (1+x^2+y^2)": (lambda: bound((_xy()[0]**2 + _xy()[1]**2 + 1) * (
        _xy()[0]**4 * _xy()[1]**2 + _xy()[0]**2 * _xy()[1]**4 + 1 - 3 * _xy()[0]**2 * _xy()[1]**2)), 0.0),
    "sdsos": (lambda: bound(_x()**2 + _x() + 1, cone="sdsos"), 0.75),
}


def mosek_works() -> bool:
    import cvxpy as cp
    if "MOSEK" not in cp.installed_solvers():
        return False
    return bound(_x()**2).solve(solver="MOSEK", backend="cvxpy").status == "optimal"   # else: no licence


@pytest.mark.parametrize("solver", ["CLARABEL", "SCS", "CVXOPT", "MOSEK"])
@pytest.mark.parametrize("case", list(CASES))
def test_known_answers_through_cvxpy(case, solver):
    if solver == "MOSEK" and not mosek_works():
        pytest.skip("MOSEK is not installed or has no licence")
    if solver == "CVXOPT":
        pytest.importorskip("cvxopt")
    make, answer = CASES[case]
    sol = make().solve(solver=solver, backend="cvxpy", **SETTINGS[solver])
    assert sol.verified, (sol.status, sol.raw_status)
    assert sol.objective == pytest.approx(answer, abs=2e-6 * max(1.0, abs(answer)))


def test_cvxpy_and_direct_duals_agree():
    x, _ = _xy()
    prog = bound(x**4 - 3 * x**2 + 2)
    con = prog.sos_constraints[0]
    direct = prog.solve().moments(con).matrix
    pytest.importorskip("cvxopt")
    for solver in ("CLARABEL", "CVXOPT"):
        assert prog.solve(solver=solver, backend="cvxpy").moments(con).matrix == pytest.approx(direct, abs=2e-3)  # CVXOPT 7e-4

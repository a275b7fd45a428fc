"""The compressed data term, named term tables and the solve policy of the convex steps."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.fit.steps.common import LeastSquaresData, TermTable, solve_with_fallback
from sosdyn.sos import backends


def test_compressed_cost_equals_the_mean_squared_residual():
    rng = np.random.default_rng(1)
    T, K, n, m = 80, 3, 2, 4
    H = rng.dirichlet(np.ones(K), size=T)
    Phi, Zdot, C = rng.normal(size=(T, m)), rng.normal(size=(T, n)), rng.normal(size=(K, n, m))
    data = LeastSquaresData(H, Phi, Zdot)
    pred = np.einsum("tk,kij,tj->ti", H, C, Phi)
    assert np.isclose(data.cost(C), ((pred - Zdot) ** 2).sum() / T, rtol=1e-12)
    assert data.shape == (K, n, m)


def test_term_table_orders_weights_by_name_and_refuses_wrong_names():
    table = TermTable({"b": "B", ("a", 1): "A1", "c": "C"})
    assert table.names == ("b", ("a", 1), "c") and table.terms == ["B", "A1", "C"]
    np.testing.assert_array_equal(table.weights({"c": 3.0, "b": 1.0, ("a", 1): 2.0}), [1.0, 2.0, 3.0])
    with pytest.raises(sd.InputError, match=r"missing \['c'\], unknown \[\]"):
        table.weights({"b": 1.0, ("a", 1): 2.0})
    with pytest.raises(sd.InputError, match=r"unknown \['d'\]"):
        table.weights({"b": 1.0, ("a", 1): 2.0, "c": 3.0, "d": 4.0})


def test_infeasibility_is_raised_without_a_fallback():
    (x,) = sd.variables("x")
    prog = sd.SOSProgram("infeasible")
    g = prog.new_var()
    prog.add_sos(-(x**2) - 1 + 0 * g)
    solvers = []
    real = prog.solve
    prog.solve = lambda solver, **kw: solvers.append(solver) or real(solver=solver, **kw)
    with pytest.raises(sd.InfeasibleError):
        solve_with_fallback(prog, "CLARABEL")
    assert solvers == ["CLARABEL"]


def test_an_unverified_clarabel_answer_is_retried_with_tighter_tolerances_first(monkeypatch):
    (x,) = sd.variables("x")
    prog = sd.SOSProgram("retry")
    g = prog.new_var()
    prog.add_sos(x**2 + 1 - g)
    prog.maximize(g)
    real, calls = backends._clarabel, []

    def spoiled_once(data, verbose, settings):        # the first answer fails the independent check
        calls.append(sorted(settings))
        status, x_, raw, seconds, info = real(data, verbose, settings)
        return status, (x_ + 1.0 if len(calls) == 1 else x_), raw, seconds, info
    monkeypatch.setattr(backends, "_clarabel", spoiled_once)
    sol = solve_with_fallback(prog, "CLARABEL")
    assert calls[0] == [] and {"tol_feas", "tol_gap_abs", "tol_gap_rel"} <= set(calls[1]) and len(calls) == 2
    assert sol.info["fallback"].startswith("CLARABEL with tighter tolerances after CLARABEL: optimal")
    assert abs(sol.value(g) - 1.0) < 1e-6

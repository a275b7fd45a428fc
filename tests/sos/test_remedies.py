"""Retries after numerical failures and the right diagnosis of "unbounded" (sosdyn.sos.remedies).

Known answers: Broyden tridiagonal and chained singular are sums of squares vanishing at a real
point, so max g with f - g SOS is 0 (a returned bound must be <= 0 up to the check's slack);
the Motzkin polynomial is nonnegative but not SOS; x + y on {1 - x^2 >= 0} has min -inf.
"""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.sos import BasicSet, backends, minimize_on


def chain(n):
    return sd.variables(" ".join(f"x{i}" for i in range(n)))


def broyden(n):
    xs = [0] + list(chain(n)) + [0]
    return sum(((3 - 2 * xs[i]) * xs[i] - xs[i - 1] - 2 * xs[i + 1] + 1) ** 2 for i in range(1, n + 1))


def chained_singular(n):
    xs = chain(n)
    return sum((a + 10 * b) ** 2 + 5 * (c - d) ** 2 + (b - 2 * c) ** 4 + 10 * (a - 10 * d) ** 4
               for a, b, c, d in (xs[i:i + 4] for i in range(0, n - 3, 2)))


def lower_bound(p, **solve):
    prog = sd.SOSProgram()
    g = prog.new_var()
    prog.add_sos(p - g, sparsity="correlative")
    prog.maximize(g)
    return prog.solve(**solve), g


def failing_first(monkeypatch, how):
    """Make the first Clarabel solve of a test fail in a given way (``how(result)`` -> result), so the
    remedies are exercised whatever this machine's Clarabel does with the program itself."""
    calls = []
    real = backends._clarabel

    def patched(data, verbose, settings):
        out = real(data, verbose, settings)
        calls.append(dict(settings))
        return how(out) if len(calls) == 1 else out
    monkeypatch.setattr(backends, "_clarabel", patched)
    return calls


def test_a_numerical_error_is_retried_with_another_remedy(monkeypatch):
    # Broyden n = 6 (minimum 0): whatever the solver does first, a numerical error is retried and
    # the answer taken is one that passes; its bound is a bound (<= 0) and close
    calls = failing_first(monkeypatch, lambda out: ("solver_error", out[1] * np.nan, "NumericalError", *out[3:]))
    sol, g = lower_bound(broyden(6))
    attempts = sol.info["attempts"]
    assert attempts[0]["status"] == "solver_error" and attempts[-1]["passed"] and len(calls) == len(attempts)
    assert sol.usable and -1e-5 <= sol.value(g) <= 0.0
    assert sol.timings["retries"] > 0
    failing_first(monkeypatch, lambda out: ("solver_error", out[1] * np.nan, "NumericalError", *out[3:]))
    refused, _ = lower_bound(broyden(6), retry=False)
    assert refused.status == "solver_error" and len(refused.info["attempts"]) == 1


def test_an_answer_failing_the_check_is_retried_until_one_passes(monkeypatch):
    # the first answer spoiled (a Gram entry off by 1 % of the largest entry, a coefficient residual far
    # above the check's 1e-6 of the coefficients' scale on any machine; 1e-3 absolute passed where the
    # solver's answer had room, e.g. OPENBLAS_CORETYPE=Nehalem); a remedy's answer
    # passes. The bound itself: chained singular has its minimum 0 at x = 0, where z(0) is the
    # constant monomial alone, so every exact Gram matrix is singular in directions without it:
    # a value is proven (<= 0) or refused, typed, saying what was tried
    def spoil(out):
        x = out[1].copy()
        x[-1] += 1e-2 * np.abs(x).max()
        return (out[0], x, *out[2:])
    failing_first(monkeypatch, spoil)
    sol, g = lower_bound(chained_singular(16))
    steps = [a["passed"] for a in sol.info["attempts"]]
    assert not steps[0] and steps[-1] and sol.usable
    try:
        assert -1e-3 <= sol.value(g) <= 0.0
    except sd.UnverifiedSolutionError as exc:
        assert "Tried" in str(exc)


@pytest.mark.parametrize("n, sparsity", [(4, None), (8, "correlative")])
def test_chained_singular_is_never_bounded_above_its_minimum(n, sparsity):
    # f(0) = 0 and f >= 0 (a sum of even powers): min f = 0. Its certificates are singular where no
    # remedy has reached them; whatever the remedies find, a returned bound is <= 0, else the
    # refusal is typed and says what was tried
    f = chained_singular(n)
    assert f([[0.0] * n])[0] == 0.0
    try:
        lb = minimize_on(f, sparsity=sparsity)
    except sd.UnverifiedSolutionError as exc:
        assert "Tried" in str(exc)
    else:
        assert lb.value <= 0.0


def test_remedies_never_override_a_setting_the_user_gave():
    sol, _ = lower_bound(chained_singular(16), static_regularization_constant=1e-8)
    for a in sol.info["attempts"]:
        assert a["settings"]["static_regularization_constant"] == 1e-8


def test_unbounded_over_an_infeasible_sos_constraint_is_infeasible():
    # maximise t, which no constraint mentions, subject to "Motzkin is SOS" (false): Clarabel
    # reports dual infeasibility; the constraints alone are infeasible
    x, y = sd.variables("x y")
    prog = sd.SOSProgram()
    t = prog.new_var()
    prog.add_sos(x**4 * y**2 + x**2 * y**4 - 3 * x**2 * y**2 + 1)
    prog.maximize(t)
    sol = prog.solve()
    with pytest.raises(sd.InfeasibleError, match="infeasible"):          # never "unbounded"
        sol.value(t)
    # a bounded-above objective over feasible constraints is still reported unbounded
    prog = sd.SOSProgram()
    t = prog.new_var()
    prog.add_sos(x**2 + 1)
    prog.maximize(t)
    with pytest.raises(sd.UnboundedError):
        prog.solve().value(t)


@pytest.mark.parametrize("kw", [{"degree": 4}, {}, {"sparsity": "correlative"}])
def test_a_free_variable_of_odd_degree_is_named_as_the_cause(kw):
    # min x + y on |x| <= 1 with y free is -inf: with degree 4 the dense multiplier basis holds y
    # and Clarabel stopped with NumericalError ("rescale the data"); now the cause is named
    x, y = sd.variables("x y")
    with pytest.raises(sd.InfeasibleError, match="no finite lower bound on the set"):
        minimize_on(x + y, BasicSet([1 - x**2]), **kw)                  # a ray, proven before any solve
    prog = sd.SOSProgram()                                              # the program itself, solved
    g = prog.new_var()
    prog.add_nonneg_on(x + y - g, BasicSet([1 - x**2]), **{k: v for k, v in kw.items() if k == "degree"})
    prog.maximize(g)
    with pytest.raises(sd.InfeasibleError, match="odd degree 1 in y, which no constraint of the set mentions"):
        prog.solve().value(g)
    assert minimize_on(x + y**2, BasicSet([1 - x**2]), degree=2).value == pytest.approx(-1.0, abs=1e-6)

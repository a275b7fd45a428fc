"""The bad-input catalogue (docs/errors.md): every case must raise a typed SosdynError whose
message says what was wrong; none may end in a bare traceback, a NaN or a silent answer."""
import functools
import json

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.fit.warp import LIP_FACTOR, check_maps
from sosdyn.poly import PolyMatrix
from sosdyn.sos.moments import Moments


def _demos(goals=((0.0, 0.0), (0.0, 0.0)), T=50, nan=False, dims=None):
    out = []
    for i, g in enumerate(goals):
        t = np.linspace(0, 1, T)
        pos = np.column_stack([np.linspace(5 + i, g[0], T), np.linspace(-3 - i, g[1], T)])
        if dims:
            pos = np.column_stack([pos] + [np.linspace(1, 0, T)] * (dims[i] - 2))
        if nan and i == 1:
            pos[10, 0] = np.nan
        out.append(Demonstration(t, pos, np.gradient(pos, t, axis=0), source=f"d{i}"))
    return Demonstrations(out, name="synthetic")


@functools.cache
def _fitted_once():
    return sd.CDSP(n_components=1, gamma=0.5, warp="none").fit(_demos())


@pytest.fixture(scope="module")
def fitted():
    return _fitted_once()


def _bump(lip):
    """One warp bump (centers, vectors, sigmas) with Lipschitz number ``lip``."""
    return np.array([[0.3, 0.0]]), np.array([[lip * 0.5 / LIP_FACTOR, 0.0]]), np.array([0.5])


def _rollout_over_budget(model):
    with sd.limits(max_rollout_calls=20):
        return model.rollout([1.0, 2.0], duration=100.0)


x, y = sd.variables("x y")


def _prog_without_objective_value():
    prog = sd.SOSProgram()
    prog.add_sos(x**2 + 1)
    return prog.solve().objective


def _limited(call, max_bytes=2**16):
    with sd.limits(max_bytes=max_bytes):
        return call()


def _minimizers(p):
    lb = sd.minimize_on(p)
    return lb.solution.minimizers(lb.constraint)


def _tampered(fitted, tmp_path, edit):
    path = tmp_path / "m.json"
    fitted.save(path)
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    return sd.load_model(path)


CATALOGUE = [
    # polynomial layer
    ("negative power", lambda: x ** -2, sd.PolynomialError, "non-negative integer"),
    ("bilinear product of decisions", lambda: (lambda p: p.new_var() * p.new_var())(sd.SOSProgram()),
     sd.PolynomialError, "bilinear"),
    ("evaluate with too many columns", lambda: (x + y)(np.ones((2, 3)), ["x", "y"]), sd.PolynomialError, "columns"),
    ("evaluate without a value for a variable", lambda: (x * y)(np.ones((2, 1)), ["x"]), sd.PolynomialError, "no value"),
    ("evaluate a decision polynomial numerically", lambda: sd.SOSProgram().new_poly([x], 2)(np.ones((1, 1)), ["x"]),
     sd.PolynomialError, "decision"),
    ("matrix product of mismatched shapes", lambda: PolyMatrix([[x, y]]) @ np.ones((3, 1)), sd.PolynomialError, "cannot multiply"),
    ("matrix entry that is not a polynomial", lambda: PolyMatrix([["a", x]]), sd.PolynomialError, "neither"),
    ("non-polynomial sympy expression", lambda: sd.from_sympy("sin(x)", ["x"]), sd.PolynomialError, "not a polynomial"),
    ("duplicate variable names", lambda: sd.variables("x y x"), sd.PolynomialError, "duplicate"),
    ("substitute an unknown variable", lambda: (x + 1).subs({"q": 1.0}), sd.PolynomialError, "cannot substitute"),
    # SOS layer
    ("non-symmetric matrix to add_sos_matrix", lambda: sd.SOSProgram().add_sos_matrix(PolyMatrix([[x, y], [0, x]])),
     sd.NotSymmetricError, "not symmetric"),
    ("non-square matrix to add_sos_matrix", lambda: sd.SOSProgram().add_sos_matrix(PolyMatrix([[x, y]])),
     sd.NotSymmetricError, "square"),
    ("SOS polynomial of odd degree", lambda: sd.SOSProgram().new_sos([x], 3), sd.PolynomialError, "even degree"),
    ("objective that depends on x", lambda: sd.SOSProgram().minimize(x), sd.PolynomialError, "must not depend on x"),
    ("maximise a convex quadratic", lambda: sd.SOSProgram().maximize(sd.sum_squares([x - x + 1])), sd.InputError, "not a convex"),
    ("unknown solver", lambda: sd.SOSProgram().solve(solver="GUROBI_MAYBE"), sd.InputError, "unknown solver"),
    ("unknown backend", lambda: sd.SOSProgram().solve(backend="magic"), sd.InputError, "unknown backend"),
    ("add_sos of a PolyMatrix", lambda: sd.SOSProgram().add_sos(PolyMatrix([[x]])), sd.PolynomialError, "add_sos_matrix"),
    ("repeated monomials in a basis", lambda: sd.SOSProgram().add_sos(x**2, basis=[x, x]), sd.PolynomialError, "repeated"),
    ("objective value of an infeasible program", lambda: (lambda p: (p.add_sos(-x**2 - 1), p.minimize(0.0), p.solve().objective))(sd.SOSProgram()),
     sd.InfeasibleError, "infeasible"),
    ("multiplier degree below the constraint's", lambda: sd.SOSProgram().add_nonneg_on(x, ineqs=[1 - x**4], degree=2),
     sd.PolynomialError, "below the degree"),
    ("empty box (lower above upper)", lambda: sd.BasicSet.box([x], 1, -1), sd.InputError, "empty"),
    ("ball of negative radius", lambda: sd.BasicSet.ball([x], -1), sd.InputError, "empty"),
    ("non-finite ball radius", lambda: sd.BasicSet.ball("x", float("nan")), sd.InputError, "finite"),
    ("ball radius whose square overflows", lambda: sd.BasicSet.ball("x", 1e200), sd.InputError, "squared"),
    ("box over something that is not a variable", lambda: sd.BasicSet.box([x**2], 0, 1), sd.InputError,
     "takes variables"),
    ("box bounds of the wrong length", lambda: sd.BasicSet.box("x y", [0, 0, 0], 1), sd.InputError, "2 numbers"),
    ("ball center of the wrong length", lambda: sd.BasicSet.ball("x y", 1, center=[1, 2, 3]), sd.InputError,
     "center"),
    ("one polynomial as a set's ineqs", lambda: sd.BasicSet(x), sd.InputError, "list of polynomials"),
    ("a repeated variable in a box", lambda: sd.BasicSet.ball([x, x], 1), sd.InputError, "repeated"),
    ("intersection with something that is not a set", lambda: sd.BasicSet.box("x", 0, 1) & 5, sd.InputError,
     "intersects two BasicSets"),
    ("a multiplier degree that is not an int", lambda: sd.minimize_on(x * y, sd.BasicSet.box("x y", -1, 1), degree=2.5),
     sd.InputError, "degree must be an int"),
    ("a string as the multiplier degree", lambda: sd.minimize_on(x * y, sd.BasicSet.box("x y", -1, 1), degree="4"),
     sd.InputError, "degree must be an int"),
    ("products that is not a bool or an int", lambda: sd.minimize_on(x * y, sd.BasicSet.box("x y", -1, 1), degree=2,
                                                                      products="yes"), sd.InputError, "products must be"),
    ("moment of an exponent tuple of the wrong length",
     lambda: Moments(("x", "y"), np.zeros((1, 2), int), np.eye(1), np.zeros((1, 2), int), np.ones(1)).moment((1,)),
     sd.InputError, "one exponent per variable"),
    ("Gram basis over the memory limit", lambda: _limited(lambda: sd.SOSProgram().add_sos(
        sum(v**2 for v in sd.variables(" ".join(f"v{i}" for i in range(60)))))), sd.ResourceLimitError, "max_bytes"),
    ("SOS matrix family over the memory limit", lambda: _limited(lambda: sd.SOSProgram().add_sos_matrix_family(
        [PolyMatrix([[x**2 + 1, x * y], [x * y, y**2 + 1]])] * 40, np.ones(40)), 2**10), sd.ResourceLimitError, "family"),
    ("minimiser that does not attain the bound", lambda: _minimizers((x**2 - 1) ** 2 + 1e-6 * x), sd.NoAtomsError,
     "attains the bound"),
    # demonstrations
    ("NaN in a demonstration", lambda: sd.CDSP().fit(_demos(nan=True)), sd.DemonstrationError, "NaN"),
    ("demonstrations that do not share a goal", lambda: sd.CDSP().fit(_demos(goals=((0, 0), (4, 4)))),
     sd.DemonstrationError, "goal|end"),
    ("a demonstration with too few samples", lambda: sd.CDSP().fit(_demos(T=3)), sd.DemonstrationError, "samples"),
    ("demonstrations of different dimensions", lambda: sd.CDSP().fit(_demos(dims=(2, 3))), sd.DemonstrationError, "dimension"),
    ("no demonstrations at all", lambda: sd.CDSP().fit(Demonstrations([])), sd.DemonstrationError, "demonstration"),
    ("unknown LASA shape", lambda: sd.load_lasa("Leaf3"), sd.InputError, "Did you mean"),
    ("demo file that does not exist", lambda: sd.load_demos(["/nonexistent/demo.csv"]), sd.SosdynError, "demo.csv"),
    # learner hyper-parameters
    ("odd metric degree", lambda: sd.CDSP(metric_degree=3).fit(_demos()), sd.InputError, "odd"),
    ("even field degree (no certificate can exist)", lambda: sd.CDSP(field_degree=2).fit(_demos()), sd.InputError, "even"),
    ("negative contraction rate", lambda: sd.CDSP(gamma=-0.1).fit(_demos()), sd.InputError, "gamma"),
    ("more components than the data supports", lambda: sd.CDSP(n_components=40).fit(_demos()), sd.InputError, "too few"),
    # issue 23: exports, warps, corrective refits
    ("units that could carry code into an export", lambda: Demonstrations([], units="coding:unicode_escape\\nprint(1)#"),
     sd.InputError, "each a letter, a digit or one of"),
    ("export to an unknown target", lambda: _fitted_once().export("rust"), sd.InputError, "unknown export target"),
    ("a near-singular warp", lambda: check_maps(*_bump(1 - 1e-13), np.zeros(2)), sd.InputError, "near singular"),
    ("a warp of more than 10,000 bumps", lambda: check_maps(*(np.repeat(a, 10_001, axis=0) for a in _bump(1e-6)),
                                                             np.zeros(2)), sd.InputError, "more than 10000"),
    ("corrective_tau shorter than the sample step",
     lambda: sd.CDSP(corrective_rounds=1, corrective_tau=1e-12).fit(_demos()), sd.InputError, "shorter than the demonstrations"),
]


@pytest.mark.parametrize("what, call, exc, match", CATALOGUE, ids=[c[0] for c in CATALOGUE])
def test_catalogue(what, call, exc, match):
    with pytest.raises(exc, match=match) as info:
        call()
    assert isinstance(info.value, sd.SosdynError)
    assert len(str(info.value)) > 20          # a sentence, not a bare token


@pytest.mark.parametrize("what, call, match", [
    ("predict with wrong dimension", lambda m: m.predict(np.zeros((4, 3))), "shape"),
    ("predict with NaN", lambda m: m.predict([[np.nan, 1.0]]), "NaN"),
    ("rollout from a wrong-sized start", lambda m: m.rollout([1.0, 2.0, 3.0], duration=1.0), "shape"),
    ("rollout with a non-positive duration", lambda m: m.rollout([1.0, 2.0], duration=0.0), "duration"),
    ("rollout with a push after the end", lambda m: m.rollout([1.0, 2.0], duration=1.0, perturbations=[(5.0, [1, 1])]), "5"),
    ("rollout over max_rollout_calls", _rollout_over_budget, "stopped after 21 field calls"),
])
def test_model_boundary(fitted, what, call, match):
    with pytest.raises(sd.SosdynError, match=match):
        call(fitted)


@pytest.mark.parametrize("what, edit, match", [
    ("edited array", lambda d: d["state"]["C_"][0][0].__setitem__(0, 3.0), "checksum"),
    ("wrong format", lambda d: d.__setitem__("format", "other"), "not a sosdyn-cdsp"),
    ("future version", lambda d: d.__setitem__("version", 99), "version"),
    ("missing state", lambda d: (d.__setitem__("state", {}), d.__setitem__("sha256", __import__("sosdyn.lfd.model.fileformat", fromlist=["_digest"])._digest({k: v for k, v in d.items() if k != "sha256"}))), "malformed"),
])
def test_tampered_model_files(fitted, tmp_path, what, edit, match):
    with pytest.raises(sd.ModelFileError, match=match):
        _tampered(fitted, tmp_path, edit)


def test_catalogue_is_large_and_documented():
    from pathlib import Path
    doc = (Path(__file__).parents[1] / "docs" / "errors.md").read_text()
    assert len(CATALOGUE) + 9 >= 30
    missing = [c[0] for c in CATALOGUE if c[0] not in doc]
    assert not missing, f"cases missing from docs/errors.md: {missing}"

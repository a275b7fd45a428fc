"""``python -m problems.bench.sos_issue32``: the known-answer problems of issue 32, as an outside
user writes them, with what sosdyn returns, the exact answer, and how the proven point was found.

Each row: the returned number (or the typed error), the exact value (closed form or sympy), the
distance, the remedy (``Solution.proof.method``) and the seconds. A returned lower bound above the
exact minimum (or an upper bound below the maximum) is a failure of the row (``ok`` False), as is
a verified certificate of a claim known to be false. Writes ``sos_issue32.json`` and ``.md`` in
``--out`` (default reports/bench). ``--quick``: the fast rows only.
"""
from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from fractions import Fraction
from pathlib import Path

import sympy

import sosdyn as sd
from sosdyn.errors import SosdynError
from sosdyn.poly import PolyMatrix
from sosdyn.sos import LowerBound

X, Y = sd.variables("x y")
P1 = X**2 + 24 * X**3 + 0.1 * X**4
BEALE = (1.5 - X + X * Y) ** 2 + (2.25 - X + X * Y**2) ** 2 + (2.625 - X + X * Y**3) ** 2
SHIFTED = (100 * X - 1) ** 2 + (Y / 100 - 2) ** 2 + (X * Y - 2) ** 2 + 3


def univariate_minimum(c) -> float:
    """min of sum c_k t^k by sympy's real roots of the derivative (exact rational coefficients)."""
    t = sympy.Symbol("t")
    p = sum(sympy.Rational(Fraction(ci)) * t**k for k, ci in enumerate(c))
    return float(min(p.subs(t, r).evalf(30) for r in sympy.Poly(sympy.diff(p, t), t).real_roots()))


def bound_program(write):
    """A bound program of P1 written one way; returns the value of its bound."""
    prog = sd.SOSProgram()
    g = prog.new_var(name="g")
    bound = write(prog, g)
    return prog.solve().value(bound)


REWRITES = {
    "maximize(g)": lambda prog, g: (prog.add_sos(P1 - g), prog.maximize(g), g)[-1],
    "minimize(-g)": lambda prog, g: (prog.add_sos(P1 - g), prog.minimize(-g), g)[-1],
    "row g >= -1e12": lambda prog, g: (prog.add_sos(P1 - g), prog.add_ge(g, -1e12), prog.maximize(g), g)[-1],
    "row g <= 1e12": lambda prog, g: (prog.add_sos(P1 - g), prog.add_ge(1e12 - g), prog.maximize(g), g)[-1],
    "g + h, h = 0": lambda prog, g: _split(prog, g),
    "g bounds p and p + 1": lambda prog, g: (prog.add_sos(P1 - g), prog.add_sos(P1 + 1 - g), prog.maximize(g), g)[-1],
    "1 x 1 SOS matrix": lambda prog, g: (prog.add_sos_matrix(PolyMatrix([[P1 - g]])), prog.maximize(g), g)[-1],
    "maximize(expr(g))": lambda prog, g: (prog.add_sos(P1 - g), prog.maximize(prog.expr(g)), g)[-1],
    "minimize t, t + p SOS": lambda prog, g: (prog.add_sos(g + P1), prog.minimize(g), -g)[-1],
}


def _split(prog, g):
    h = prog.new_var(name="h")
    prog.add_eq(h, 0.0)
    prog.add_sos(P1 - g - h)
    prog.maximize(g)
    return g


def lyapunov(degree):
    """x' = -x + xy, y' = -y has no polynomial Lyapunov function: any verified V is a failure."""
    prog = sd.SOSProgram()
    V = prog.new_poly([X, Y], degree, min_degree=2)
    Vdot = V.diff("x") * (-X + X * Y) + V.diff("y") * (-Y)
    prog.add_sos(V - 0.01 * (X**2 + Y**2))
    prog.add_sos(-Vdot - 0.01 * (X**2 + Y**2))
    sol = prog.solve()
    if sol.verified:
        raise AssertionError("a Lyapunov function was verified for a system that has none")
    sol.value(V)


def vv_t():
    prog = sd.SOSProgram()
    prog.add_sos_matrix(PolyMatrix([[1 + X**2, X * Y**2], [X * Y**2, 1 + Y**4]]))
    return 1.0 if prog.solve().verified else 0.0


def chebyshev_shifted():
    (t,) = sd.variables("t")
    s = t - 2
    return sd.minimize_on(64 * s**7 - 112 * s**5 + 56 * s**3 - 7 * s, sd.BasicSet.box([t], 1, 3), degree=8)


def broyden(n):
    xs = [0] + list(sd.variables(" ".join(f"x{i}" for i in range(n)))) + [0]
    return sum(((3 - 2 * xs[i]) * xs[i] - xs[i - 1] - 2 * xs[i + 1] + 1) ** 2 for i in range(1, n + 1))


def rosenbrock(n):
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    return sum(100 * (xs[i + 1] - xs[i] ** 2) ** 2 + (1 - xs[i]) ** 2 for i in range(n - 1))


def chain_sum(n=12):
    xs = sd.variables(" ".join(f"x{i}" for i in range(n)))
    lb = sd.minimize_on(sum(xs), sd.BasicSet(ineqs=[1 - xs[i]**2 - xs[i + 1]**2 for i in range(n - 1)]), degree=2)
    lb.minimizers()
    return lb


def disc_cut():
    lb = sd.minimize_on(X, sd.BasicSet(ineqs=[1 - X**2 - Y**2, Y - 0.5]), degree=2)
    lb.solution.minimizers(lb.constraint)
    return lb


P1_MIN = univariate_minimum([0.0, 0.0, 1.0, 24.0, 0.1])
#: name -> (callable returning a LowerBound, a number, or raising; exact value or the expected error; sense, quick)
ROWS = {**{f"x^2+24x^3+0.1x^4: {k}": (lambda w=w: bound_program(w), P1_MIN, "lower", True) for k, w in REWRITES.items()},
        "x^2+24x^3+0.1x^4: minimize_on": (lambda: sd.minimize_on(P1), P1_MIN, "lower", True),
        "x^4-x^2, row g <= 1e6": (lambda: bound_program(lambda prog, g: (prog.add_sos(X**4 - X**2 - g),
                                                                          prog.add_ge(1e6 - g), prog.maximize(g), g)[-1]),
                                  -0.25, "lower", True),
        "xy on [-50, 80]^2, degree 2": (lambda: sd.minimize_on(X * Y, sd.BasicSet.box("x y", -50, 80), degree=2),
                                        -4000.0, "lower", True),
        "xy on [-50, 80]^2, degree 4": (lambda: sd.minimize_on(X * Y, sd.BasicSet.box("x y", -50, 80), degree=4),
                                        -4000.0, "lower", True),
        "xy on [-750, 750] x [-7.5e-4, 7.5e-4]": (lambda: sd.minimize_on(
            X * Y, sd.BasicSet.box("x y", [-750, -7.5e-4], [750, 7.5e-4]), degree=2), -0.5625, "lower", True),
        "T7(t - 2) on [1, 3]": (chebyshev_shifted, -1.0, "lower", True),
        "Beale": (lambda: sd.minimize_on(BEALE), 0.0, "lower", True),
        "(100x-1)^2 + (y/100-2)^2 + (xy-2)^2 + 3": (lambda: sd.minimize_on(SHIFTED), 3.0, "lower", True),
        "the same, rigorous=True": (lambda: sd.minimize_on(SHIFTED, rigorous=True), 3.0, "lower", True),
        "the same, SCS": (lambda: sd.minimize_on(SHIFTED, solver="SCS"), 3.0, "lower", False),
        "Broyden tridiagonal n = 40, correlative": (lambda: sd.minimize_on(broyden(40), sparsity="correlative"),
                                                    0.0, "lower", False),
        "chained Rosenbrock n = 20, correlative (minimiser x = 1)": (
            lambda: sd.minimize_on(rosenbrock(20), sparsity="correlative"), 0.0, "lower", True),
        "chained Rosenbrock n = 8, dense (minimiser x = 1)": (lambda: sd.minimize_on(rosenbrock(8)), 0.0, "lower", False),
        "min x, unit disc and y >= 1/2 (atoms)": (disc_cut, -math.sqrt(3) / 2, "lower", True),
        "min sum x_i, x_i^2 + x_(i+1)^2 <= 1, n = 12 (atoms)": (chain_sum, -6 * math.sqrt(2), "lower", True),
        "v v^T + I is an SOS matrix (1 = verified)": (vv_t, 1.0, "equal", True),
        "min x - y on y >= x^2, degree 4": (lambda: sd.minimize_on(X - Y, sd.BasicSet([Y - X**2]), degree=4),
                                            "InfeasibleError", "error", True),
        "min xy on x >= 1, y <= -1, degree 4": (lambda: sd.minimize_on(X * Y, sd.BasicSet([X - 1, -1 - Y]), degree=4),
                                                "InfeasibleError", "error", True),
        "min x on xy >= 1, x >= 0, degree 4": (lambda: sd.minimize_on(X, sd.BasicSet([X * Y - 1, X]), degree=4),
                                               0.0, "lower", True),
        "Lyapunov V, x' = -x + xy, degree 4": (lambda: lyapunov(4), "SolverError", "error", True),
        "Lyapunov V, x' = -x + xy, degree 6": (lambda: lyapunov(6), "SolverError", "error", True)}


def run_row(name, make, exact, kind) -> dict:
    t0 = time.perf_counter()
    row = {"name": name, "exact": exact}
    try:
        out = make()
    except SosdynError as exc:
        row.update(returned=type(exc).__name__, ok=kind == "error" and isinstance(exc, getattr(sd, exact)),
                   detail=str(exc)[:160])
    else:
        value = float(out.value) if isinstance(out, LowerBound) else float(out)
        method = out.solution.proof.method if isinstance(out, LowerBound) and not out.solution.rigorous else ""
        ok = {"lower": value <= exact, "equal": value == exact}.get(kind, False)
        row.update(returned=value, ok=ok, method=method,
                   relative=abs(value - exact) / max(1.0, abs(exact)) if kind != "error" else None)
    row["seconds"] = time.perf_counter() - t0
    return row


def markdown(rows) -> str:
    lines = ["| problem | returned | exact | distance (relative) | how | ok | s |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        ret = r["returned"] if isinstance(r["returned"], str) else f"{r['returned']:.12g}"
        dist = "" if r.get("relative") is None else f"{r['relative']:.1e}"
        lines.append(f"| {r['name']} | {ret} | {r['exact']} | {dist} | {r.get('method', '')} | "
                     f"{'yes' if r['ok'] else 'NO'} | {r['seconds']:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default="reports/bench")
    args = ap.parse_args(argv)
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, (make, exact, kind, quick) in ROWS.items():
            if quick or not args.quick:
                rows.append(run_row(name, make, exact, kind))
                print(markdown(rows[-1:]).splitlines()[-1], flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "sos_issue32.json").write_text(json.dumps(rows, indent=1))
    (out / "sos_issue32.md").write_text(markdown(rows))
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())

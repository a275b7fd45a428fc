"""Where the time of a small SOS problem goes: the build split by stage and library, and the
floor of a sosdyn solve.

* :func:`build_split` -- the two stages of one build (the polynomial expression, then the SOS
  constraint on it) in sosdyn, SumOfSquares.py and Drake;
* :func:`floor` -- the fixed cost no Python-side speed-up removes: the Clarabel call itself, from
  Python, on the finished matrices (scipy CSC matrices and cone list -> ``DefaultSolver`` ->
  ``solve``), and inside it Clarabel's own time. Set against Drake's total on the problems Drake
  solves in under ``FLOOR_BELOW_S`` (``sos_report.floor_section``), it shows how much of Drake's
  time a sosdyn solve has left for everything written in Python.
"""
from __future__ import annotations

import clarabel
import numpy as np

import sosdyn as sd
from sosdyn.sos.backends import clarabel_problem
from sosdyn.sos.conic import affine_cones

from . import drake_problems
from .timing import median, now

FLOOR_BELOW_S = 2e-3     # problems whose Drake total is below this get a floor row


def like_drake(d) -> dict:
    """Our stages split as Drake's are: build; canonicalise = the whole ``prog.solve()`` wall time
    except the independent check and Clarabel's own time (conic assembly, lowering, the Python ->
    Clarabel call, reading the answer back); solve = Clarabel's own time (its ``solve_time``, as
    Drake reports it). The independent check (``verify``), which Drake does not do, is left out."""
    return {"build": d["build"], "canonicalize": d["canonicalize_like_drake"], "solve": d["solver_own"],
            "verify": d["verify"]}


def floor(p, reps) -> dict:
    """Median seconds (over ``reps`` calls) of the Clarabel call on problem ``p``'s finished
    matrices, from Python ("clarabel_call") and Clarabel's own part of it ("clarabel_own")."""
    prog, _ = p.ours()
    data = prog.compile()
    P, q, A, b, cones = clarabel_problem(data, affine_cones(data, enabled=False))
    opts = clarabel.DefaultSettings()
    opts.verbose = False
    wall, own = [], []
    for _ in range(reps):
        t0 = now()
        result = clarabel.DefaultSolver(P, q, A, b, cones, opts).solve()
        wall.append(now() - t0)
        own.append(float(result.solve_time))
    return {"clarabel_call": median(wall), "clarabel_own": median(own), "repetitions": reps}


def build_split(p, reps, drake_ok) -> dict | None:
    """Min and median seconds of the two stages of one build — the polynomial expression, then
    the SOS constraint on it — in sosdyn, SumOfSquares.py and Drake, for a one-polynomial
    problem (``ctx["fn"]``); None for other problems."""
    _, ctx = p.ours()
    fn = ctx.get("fn")
    if fn is None:
        return None
    names = " ".join(v.vars[0] for v in ctx["vars"])
    n = len(ctx["vars"])

    def ours_expr():
        return fn(*sd.variables(names))

    def ours_sos(e):
        sd.SOSProgram().add_sos(e)

    stages = {"sosdyn": _stages(ours_expr, ours_sos, reps)}
    try:
        import sympy
        from SumOfSquares import SOSProblem  # optional (the bench extra)
        from sympy.core.cache import clear_cache
        sparse = True                            # its Newton reduction, as in the main run
        try:
            syms = sympy.symbols(names)
            SOSProblem().add_sos_constraint(sympy.expand(fn(*syms)), list(syms), sparse=True)
        except ValueError:                       # its hull needs full-dimensional support
            sparse = False
        held = {}

        def theirs_expr():
            held["syms"] = sympy.symbols(names)
            return sympy.expand(fn(*held["syms"]))
        def theirs_sos(e):
            SOSProblem().add_sos_constraint(e, list(held["syms"]), sparse=sparse)
        stages["SumOfSquares.py"] = _stages(theirs_expr, theirs_sos, reps)
        stages["SumOfSquares.py, sympy cache cleared before each build"] = _stages(
            theirs_expr, theirs_sos, reps, before=clear_cache)
    except ImportError:
        pass
    if drake_ok:
        holder = {}

        def drake_expr():
            holder["prog"], xs = drake_problems.program(n)
            return fn(*xs)
        stages["Drake"] = _stages(drake_expr, lambda e: holder["prog"].AddSosConstraint(e), reps)
    return {"problem": p.name, "repetitions": reps, "stages": stages}


def _stages(make_expr, add_constraint, reps, before=None) -> dict:
    """Seconds (min, median) of ``make_expr()`` and ``add_constraint(expr)``; ``before()`` runs
    untimed ahead of each repetition."""
    t = {"polynomial": [], "SOS constraint": [], "total": []}
    for _ in range(reps):
        if before is not None:
            before()
        t0 = now()
        e = make_expr()
        t1 = now()
        add_constraint(e)
        t2 = now()
        t["polynomial"].append(t1 - t0)
        t["SOS constraint"].append(t2 - t1)
        t["total"].append(t2 - t0)
    return {k: {"min": float(np.min(v)), "median": median(v)} for k, v in t.items()}



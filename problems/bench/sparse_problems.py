"""Sparsity rows of ``make bench-sos``: chained Rosenbrock and chained Wood, dense Gram basis
against the sparse ones (``prog.add_sos(..., sparsity=...)``), for n = 10, 20, 30, 40.

Both are global lower bounds: maximise γ with f − γ SOS.

* chained Rosenbrock, f = Σ_{i=1}^{n−1} 100 (x_{i+1} − x_i²)² + (1 − x_i)², minimum 0 at x = 1;
* chained Wood (Waki, Kim, Kojima & Muramatsu 2006),
  f = 1 + Σ_{i∈J} [100 (x_{i+1} − x_i²)² + (1 − x_i)² + 90 (x_{i+3} − x_{i+2}²)² + (1 − x_{i+2})²
  + 10 (x_{i+1} + x_{i+3} − 2)² + 0.1 (x_{i+1} − x_{i+3})²], J = {1, 3, 5, …, n − 3},
  minimum 1 at x = 1 (every bracket is a sum of squares vanishing there). Waki et al. take n a
  multiple of 4; the formula is defined for every even n ≥ 4 (the last i = n − 3 uses x_n), which
  is how n = 10 and 30 are run here.

Every (problem, n, variant) runs in a child process with a wall-time budget: a dense
basis at n ≥ 30 is either refused by sosdyn's memory guard (``ResourceLimitError``, recorded
as "refused") or stopped at the budget (recorded as "time-limited"), never left to hang.
The sparse variants are skipped, with a note, while ``add_sos`` has no ``sparsity`` keyword.
"""
from __future__ import annotations

import multiprocessing as mp
import warnings
from dataclasses import asdict

import sosdyn as sd
from sosdyn.errors import ResourceLimitError, SosdynError

from .timing import fmt_ratio, fmt_s, md_table, now

NS = (10, 20, 30, 40)
VARIANTS = ("dense", "correlative", "correlative+term")
PROBE_S = 30.0          # budget of a variant's larger n once it ran over the full budget
ROW_PROBLEMS = ("chained Rosenbrock", "chained Wood")    # the dense-against-sparse rows (run_rows)
KNOWN_MIN = {"chained Rosenbrock": 0.0, "chained Wood": 1.0, "Broyden tridiagonal": 0.0, "chained singular": 0.0}


def balanced_sum(parts):
    """Σ parts added pairwise (a tree, not a chain): each summand is in a few variables, so the
    sum's work grows like n log n in the parts instead of n² (the bench times add_sos, not this)."""
    parts = list(parts)
    while len(parts) > 1:
        parts = [parts[k] + parts[k + 1] if k + 1 < len(parts) else parts[k] for k in range(0, len(parts), 2)]
    return parts[0]


def rosenbrock(xs):
    """Chained Rosenbrock f(x) = Σ_{i<n} 100 (x_{i+1} − x_i²)² + (1 − x_i)² (x a sequence)."""
    return balanced_sum(100 * (xs[i + 1] - xs[i]**2)**2 + (1 - xs[i])**2 for i in range(len(xs) - 1))


def wood(xs):
    """Chained Wood (module docstring), J = {1, 3, …, n − 3} in 1-based indices, n even ≥ 4."""
    n = len(xs)
    if n % 2 or n < 4:
        raise ValueError(f"chained Wood needs an even n >= 4, got {n}")
    def bracket(a, b, c, d):
        return (100 * (b - a**2)**2 + (1 - a)**2 + 90 * (d - c**2)**2 + (1 - c)**2
                + 10 * (b + d - 2)**2 + 0.1 * (b - d)**2)
    return 1 + balanced_sum(bracket(*xs[i:i + 4]) for i in range(0, n - 3, 2))   # 0-based i = j − 1, j ∈ J


def broyden(xs):
    """Broyden tridiagonal f(x) = Σ_{i=1}^n ((3 − 2 x_i) x_i − x_{i−1} − 2 x_{i+1} + 1)², x_0 = x_{n+1} = 0:
    a sum of squares whose squares vanish together at a real point, so the minimum is 0."""
    pad = [0] + list(xs) + [0]
    return balanced_sum(((3 - 2 * pad[i]) * pad[i] - pad[i - 1] - 2 * pad[i + 1] + 1)**2
                        for i in range(1, len(xs) + 1))


def chained_singular(xs):
    """Chained singular f(x) = Σ_{i∈J} (x_i + 10 x_{i+1})² + 5 (x_{i+2} − x_{i+3})² + (x_{i+1} − 2 x_{i+2})⁴
    + 10 (x_i − 10 x_{i+3})⁴, J = {1, 3, …, n − 3} (Conn, Gould & Toint): minimum 0 at x = 0."""
    return balanced_sum((a + 10 * b)**2 + 5 * (c - d)**2 + (b - 2 * c)**4 + 10 * (a - 10 * d)**4
                        for a, b, c, d in (xs[i:i + 4] for i in range(0, len(xs) - 3, 2)))


FUNCTIONS = {"chained Rosenbrock": rosenbrock, "chained Wood": wood, "Broyden tridiagonal": broyden,
             "chained singular": chained_singular}


def sparsity_supported() -> bool:
    """Whether ``SOSProgram.add_sos`` accepts ``sparsity=`` (the sparse API of issue 15), probed by
    one tiny call: the method's decorator hides its keywords from ``inspect.signature``."""
    (x,) = sd.variables("x")
    try:
        sd.SOSProgram().add_sos(x**2 + 1, sparsity="correlative")
    except TypeError:
        return False
    return True


def build(name, n, variant):
    """(program, γ): maximise γ subject to f − γ SOS with the variant's Gram basis."""
    xs = sd.variables(" ".join(f"x{i + 1}" for i in range(n)))
    prog = sd.SOSProgram(f"{name} n={n} {variant}")
    g = prog.new_var()
    kwargs = {} if variant == "dense" else {"sparsity": variant}
    prog.add_sos(FUNCTIONS[name](xs) - g, **kwargs)
    prog.maximize(g)
    return prog, g


def measure(name, n, variant) -> dict:
    """Build, solve and read the verified bound of one row (in the calling process)."""
    t0 = now()
    prog, g = build(name, n, variant)
    t_build = now() - t0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = prog.solve()
    sizes = prog.compile().sizes()
    out = {"build": t_build, "canonicalize": sol.timings["canonicalize"], "solve": sol.timings["solve"],
           "status": sol.status, "sizes": sizes, "verified": bool(sol.verified)}
    try:
        out["solver_bound"] = float(sol.solver_objective)
        out["bound"] = float(sol.value(g))
    except SosdynError as exc:
        out["bound"] = None
        out["error"] = f"{type(exc).__name__}: {str(exc)[:200]}"
    known = KNOWN_MIN[name]
    out["bound_ok"] = out["bound"] is not None and known - 1e-3 * (1 + abs(known)) <= out["bound"] <= known
    return out


def _child(conn, name, n, variant, limits):
    try:
        sd.set_limits(**asdict(limits))
        conn.send(measure(name, n, variant))
    except ResourceLimitError as exc:
        conn.send({"refused": str(exc).split("\n")[0][:300]})
    except Exception as exc:  # noqa: BLE001 -- reported in the row, the benchmark goes on
        conn.send({"error": f"{type(exc).__name__}: {str(exc)[:300]}"})
    finally:
        conn.close()


def run_budgeted(name, n, variant, budget_s) -> dict:
    """:func:`measure` in a child process under the caller's limits, stopped after ``budget_s``
    seconds of wall time. Children fork from a fresh server process that has imported this module
    but never solved ("forkserver"): a forked copy of a process whose solver thread pools already
    ran can deadlock, and a spawned one pays the imports every time."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload([__name__])
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(child, name, n, variant, sd.get_limits()), daemon=True)
    t0 = now()
    proc.start()
    child.close()
    out = parent.recv() if parent.poll(budget_s) else None
    proc.join(timeout=5 if out is not None else 0)
    if proc.is_alive():
        proc.kill()
        proc.join()
    if out is None:
        out = {"time_limited": budget_s}
    out["wall"] = now() - t0
    return out


def run_rows(ns=NS, budget_s=120.0, probe_s=PROBE_S) -> list:
    """Every (problem, n, variant) row. After a variant ran over its budget at some n, its larger
    n get only ``probe_s`` seconds: enough for the memory guard to refuse them (it checks before
    the solve starts), not to sit through another full budget."""
    sparse_ok = sparsity_supported()
    rows = []
    for name in ROW_PROBLEMS:
        limited = set()
        for n in ns:
            for variant in VARIANTS:
                if variant != "dense" and not sparse_ok:
                    res = {"skipped": "add_sos has no sparsity= keyword yet (sparse API of issue 15 not landed)"}
                else:
                    res = run_budgeted(name, n, variant, min(budget_s, probe_s) if variant in limited else budget_s)
                    if "time_limited" in res:
                        limited.add(variant)
                rows.append({"problem": name, "n": n, "variant": variant, **res})
                print(f"[bench-sos] {name} n={n} {variant}: {_cell(res)}", flush=True)
    return rows


def speedups(rows) -> list:
    """Dense total time / sparse total time for each (problem, n, sparse variant) that ran; where
    the dense row ran over its budget, budget / sparse time, a lower bound (``lower_bound``)."""
    def total(r):
        return r["build"] + r["canonicalize"] + r["solve"] if "solve" in r else None
    dense = {(r["problem"], r["n"]): r for r in rows if r["variant"] == "dense"}
    out = []
    for r in rows:
        d, t = dense.get((r["problem"], r["n"])), total(r)
        if r["variant"] == "dense" or not d or not t:
            continue
        if total(d):
            out.append({"problem": r["problem"], "n": r["n"], "variant": r["variant"],
                        "speedup": total(d) / t, "lower_bound": False})
        elif "time_limited" in d:
            out.append({"problem": r["problem"], "n": r["n"], "variant": r["variant"],
                        "speedup": d["time_limited"] / t, "lower_bound": True})
    return out


def _cell(r) -> str:
    if "skipped" in r:
        return "skipped: " + r["skipped"]
    if "refused" in r:
        return "refused by the memory guard"
    if "time_limited" in r:
        return f"time-limited (> {r['time_limited']:.0f} s)"
    if "error" in r and "solve" not in r:
        return "error: " + r["error"][:80]
    b = "refused (no safe bound)" if r.get("bound") is None else f"{r['bound']:.6g}"
    solver = f" (solver {r['solver_bound']:.3g})" if "solver_bound" in r else ""
    return (f"{r['status']}, bound {b}{solver}{'' if r.get('bound_ok') else ' ⚠'}, "
            f"{r['build'] + r['canonicalize'] + r['solve']:.3g} s")


def markdown(rows, budget_s) -> list:
    """The sparsity section of ``sos.md`` (lines)."""
    sp = {(s["problem"], s["n"], s["variant"]): ("≥ " if s["lower_bound"] else "") + fmt_ratio(s["speedup"])
          for s in speedups(rows)}

    def sizes(r):
        z = r.get("sizes")
        return f"{z['variables']} / {z['equalities']} / {max(z['psd_blocks'] or [0])}" if z else "–"

    def secs(r):
        return " / ".join(fmt_s(r[k]) for k in ("build", "canonicalize", "solve")) if "solve" in r else "–"

    table = md_table(["problem", "n", "Gram basis", "result", "build / canon / solve", "SDP vars / eqs / largest block",
                      "dense / this (total)"],
                     [[r["problem"], r["n"], r["variant"], _cell(r), secs(r), sizes(r),
                       sp.get((r["problem"], r["n"], r["variant"]), "–")] for r in rows])
    return ["## Sparsity: chained Rosenbrock and chained Wood (global lower bound, max γ with f − γ SOS)", "",
            (f"Known minima: Rosenbrock 0, Wood 1 (⚠ marks a bound above the minimum, more than 1e-3 below it, or refused: no proven point, `docs/sos-semantics.md`). Each row runs in a "
            f"child process with a {budget_s:.0f} s wall-time budget; a dense Gram basis that the memory guard "
            "refuses, or that runs over the budget, is recorded as such (\"refused\": the guard's estimate is "
            "over `max_bytes` before the solve starts). After a variant runs over the budget, its larger n get "
            f"{min(budget_s, PROBE_S):.0f} s, enough for the guard to refuse them."), "", table, ""]

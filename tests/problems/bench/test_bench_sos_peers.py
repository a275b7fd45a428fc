"""problems.bench: the Drake peer and the sparsity rows of bench-sos, on known answers."""
import numpy as np
import pytest

import sosdyn as sd
from problems.bench import catalog, drake_problems, sparse_problems
from problems.bench.sos import reps_for


def test_chained_functions_known_minima():
    ones = np.ones(8)
    assert sparse_problems.rosenbrock(ones) == 0.0
    assert sparse_problems.wood(ones) == 1.0
    # one Wood block at x = (0, 0, 0, 0): 1 + 0 + 1 + 0 + 1 + 10·4 + 0 = 43
    assert sparse_problems.wood(np.zeros(4)) == pytest.approx(43.0)
    # Rosenbrock at x = (0, 0, 0): two terms (1 − 0)² = 2
    assert sparse_problems.rosenbrock(np.zeros(3)) == pytest.approx(2.0)
    assert sparse_problems.wood(np.ones(10)) == 1.0          # n even, not a multiple of 4
    # n = 6: J = {1, 3}, two overlapping blocks at x = 0: 1 + 2 · 42 = 85
    assert sparse_problems.wood(np.zeros(6)) == pytest.approx(85.0)
    with pytest.raises(ValueError, match="even n"):
        sparse_problems.wood(np.ones(5))


def test_sparse_row_dense_bound():
    row = sparse_problems.run_budgeted("chained Wood", 4, "dense", 60.0)
    assert 1.0 - 1e-4 <= row["bound"] <= 1.0 and row["bound_ok"], row
    assert row["solver_bound"] == pytest.approx(1.0, abs=1e-4)
    assert row["build"] > 0 and row["solve"] > 0


def test_sparse_row_of_a_singular_certificate_is_bounded_by_the_minimum():
    # chained Rosenbrock: minimum 0 at x = 1 (closed form); every certificate is singular there,
    # and the bound is read on the face of the solver's kernel (docs/sos-sparsity.md)
    row = sparse_problems.run_budgeted("chained Rosenbrock", 4, "dense", 60.0)
    assert row["bound_ok"] and -1e-6 <= row["bound"] <= 0.0, row
    assert row["solver_bound"] == pytest.approx(0.0, abs=1e-4)


def test_sparse_row_refused_and_time_limited():
    with sd.limits(max_bytes=2**20):                 # the child inherits the limit
        refused = sparse_problems.run_budgeted("chained Rosenbrock", 10, "dense", 60.0)
    assert "refused" in refused and "MiB" in refused["refused"], refused
    limited = sparse_problems.run_budgeted("chained Rosenbrock", 10, "dense", 0.3)
    assert limited.get("time_limited") == 0.3 and "bound" not in limited, limited     # stopped at its budget


def test_sparse_rows_skip_or_run_the_sparse_api():
    rows = sparse_problems.run_rows(ns=(4,), budget_s=60.0)
    assert [(r["problem"], r["variant"]) for r in rows] == [
        (p, v) for p in sparse_problems.ROW_PROBLEMS for v in sparse_problems.VARIANTS]
    sparse = [r for r in rows if r["variant"] != "dense"]
    wood = [r for r in rows if r["problem"] == "chained Wood"]
    if sparse_problems.sparsity_supported():
        assert all(r.get("bound_ok") for r in wood), rows
    else:
        assert all("sparsity= keyword" in r["skipped"] for r in sparse)
    assert all(r.get("bound_ok") for r in wood if r["variant"] == "dense")
    assert all(r["bound_ok"] and -1e-6 <= r["bound"] <= 0.0            # minimum 0 at x = 1
               for r in rows if r["problem"] == "chained Rosenbrock" and "skipped" not in r)


def test_reps_for_counts():
    count = reps_for(quick=False)
    assert count(3.0, 3.0) == 1 and count(1.0, 1.0) == 2
    assert count(1e-3, 0.01) == 30 and count(1e-3, 0.6) == 3
    assert reps_for(quick=True)(1e-3, 0.0) == 1


def test_every_problem_has_a_drake_version_or_a_reason():
    for p in catalog.problems(dense_ns=(2,)):
        assert (drake_problems.builder(p) is not None) != (p.name in drake_problems.NOT_WRITTEN), p.name


@pytest.mark.parametrize("name, status, objective", [
    ("Motzkin M", "infeasible", None),
    ("probability bound (1/37)", "optimal", 1 / 37),
    ("Chebyshev (max lead coef = 128)", "optimal", -128.0),     # Drake minimises −(lead coefficient)
    ("SOS matrix", "optimal", 0.0),
    ("Choi matrix (not SOS)", "infeasible", None),
])
def test_drake_known_answers(name, status, objective):
    if drake_problems.available() is None:
        pytest.skip("pydrake (drake, the bench extra) not installed")
    p = {q.name: q for q in catalog.problems(dense_ns=(2,))}[name]
    out = drake_problems.run_drake(p, reps_for(quick=True))
    assert out["status"] == status, out
    if objective is not None:
        assert out["objective"] == pytest.approx(objective, abs=1e-5)
    assert out["build"] > 0 and out["solve"] > 0 and out["repetitions"] == 1


def test_sparse_speedups_exact_and_lower_bound():
    def ran(n, variant, seconds):
        return {"problem": "W", "n": n, "variant": variant, "build": seconds / 2, "canonicalize": 0.0,
                "solve": seconds / 2}
    rows = [ran(4, "dense", 2.0), ran(4, "correlative", 0.5),
            {"problem": "W", "n": 10, "variant": "dense", "time_limited": 120.0}, ran(10, "correlative", 1.5),
            {"problem": "W", "n": 10, "variant": "correlative+term", "skipped": "no keyword"}]
    got = sparse_problems.speedups(rows)
    assert [(s["n"], s["variant"], s["lower_bound"]) for s in got] == [(4, "correlative", False),
                                                                       (10, "correlative", True)]
    assert got[0]["speedup"] == pytest.approx(4.0) and got[1]["speedup"] == pytest.approx(80.0)

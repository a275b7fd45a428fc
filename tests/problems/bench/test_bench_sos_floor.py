"""problems.bench.sos_split: our stages split as Drake's, the floor measurement and its table."""

from problems.bench.catalog import problems
from problems.bench.sos_report import floor_section
from problems.bench.sos_split import floor, like_drake


def test_like_drake_moves_everything_but_clarabel_and_the_check_into_canonicalise():
    d = {"build": 1.0, "canonicalize_like_drake": 0.5, "solver_own": 0.25, "verify": 0.125}
    assert like_drake(d) == {"build": 1.0, "canonicalize": 0.5, "solve": 0.25, "verify": 0.125}


def test_floor_of_a_small_problem_and_its_table():
    p = next(q for q in problems(quick=True, dense_ns=(2,)) if q.name == "quartic form")
    f = floor(p, 3)
    assert 0 < f["clarabel_own"] < 0.1 and 0 < f["clarabel_call"] < 0.1 and f["repetitions"] == 3
    row = {"name": p.name, "floor": {"clarabel_call": 1e-4, "clarabel_own": 6e-5},
           "drake": {"build": 1e-4, "canonicalize": 5e-5, "solve": 5e-5},
           "direct": {"build": 2e-4, "canonicalize_like_drake": 1.5e-4, "solver_own": 5e-5, "verify": 1e-4}}
    text = "\n".join(floor_section([row, {"name": "no floor", "drake": None}]))
    assert "| quartic form | 200 µs | 400 µs | 100 µs | 60 µs | 300 µs | 50 % | 0.50× |" in text
    assert "no floor" not in text
    assert floor_section([]) == []

"""problems.bench.sos_issue32: rows are judged against the exact answers they carry."""
from problems.bench import sos_issue32 as bench


def test_rows_judge_the_side_of_the_exact_answer_and_the_typed_errors(tmp_path):
    rows = [bench.run_row(name, *bench.ROWS[name][:3]) for name in (
        "x^2+24x^3+0.1x^4: minimize(-g)", "Beale", "min x - y on y >= x^2, degree 4")]
    assert [r["ok"] for r in rows] == [True, True, True]
    assert rows[0]["returned"] <= bench.P1_MIN and rows[2]["returned"] == "InfeasibleError"
    wrong = bench.run_row("a bound above the minimum", lambda: bench.P1_MIN + 1.0, bench.P1_MIN, "lower")
    assert not wrong["ok"]
    assert "| Beale | 0 |" in bench.markdown(rows)

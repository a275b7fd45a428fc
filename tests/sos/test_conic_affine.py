"""PSD blocks imposed on their affine expressions (``affine_psd``, issue 14): which blocks are
eliminated, known answers, the full x (every block and row checked), and the per-constraint
memos of a re-solved family (same rows and structure as a fresh build)."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.poly import PolyMatrix
from sosdyn.sos import QuadraticForm
from sosdyn.sos.conic import affine_cones
from sosdyn.sos.verification import constraint_gram_structure, gram_structure

(X,) = sd.variables("x")


def _lmi_program():
    """min (t - 2)^2 + (s - 1)^2  s.t.  [[1, t], [t, 1]] SOS (a constant matrix: |t| <= 1),
    x^4 - s x^2 + 1 SOS (basis 1, x, x^2: Q_02 and Q_11 share the x^2 row; s <= 2), t + s >= 0."""
    prog = sd.SOSProgram("affine")
    t, s = prog.new_var(name="t"), prog.new_var(name="s")
    lmi = prog.add_sos_matrix(PolyMatrix([[1.0 + 0 * t, t], [t, 1.0 + 0 * t]]), name="lmi")
    poly = prog.add_sos(X**4 - s * X**2 + 1, name="quartic")
    prog.add_ge(t + s, 0.0)
    ids = np.concatenate([t.ids, s.ids])
    prog.minimize(QuadraticForm(np.eye(2), np.array([-4.0, -2.0]), 5.0, ids))
    return prog, t, s, lmi, poly


def test_only_blocks_fixed_by_their_rows_are_eliminated():
    prog, *_ = _lmi_program()
    data = prog.compile()
    red = affine_cones(data)
    by_block = {size: rows for (_, size), rows in zip(data.psd, red.rows)}
    assert by_block[2] is not None and by_block[2].size == 3       # the 2x2 constant block: 3 rows
    assert by_block[3] is None                                     # the quartic's 3x3 Gram block
    assert red.keep_cols.sum() == data.n - 3 and red.keep_rows.sum() == data.A_eq.shape[0] - 3
    assert all(r is None for r in affine_cones(data, enabled=False).rows)


def test_affine_psd_gives_the_known_answer_and_a_full_checked_x():
    prog, t, s, lmi, _ = _lmi_program()
    plain = prog.solve()
    sol = prog.solve(affine_psd=True)
    assert sol.verified and plain.verified
    assert sol.value(t) == pytest.approx(1.0, abs=1e-6) and sol.value(s) == pytest.approx(1.0, abs=1e-6)
    assert sol.x.size == plain.x.size == prog.compile().n
    Q = sol.gram_matrix(lmi)                                       # read back from the cone
    assert np.allclose(Q, [[1.0, 1.0], [1.0, 1.0]], atol=1e-6)
    assert sol.objective == pytest.approx(plain.objective, abs=1e-7) and sol.objective == pytest.approx(1.0, abs=1e-6)
    assert len(sol.info["psd_duals"]) == 2


def test_a_block_in_the_objective_or_shared_rows_stays_a_variable():
    prog = sd.SOSProgram("kept")
    P = prog.new_psd(2, name="P")                  # its entries are in the objective and in the rows
    prog.add_sos_matrix(P - 0.5 * PolyMatrix.identity(2), name="P >= I/2")
    prog.minimize(P[0, 0] + P[1, 1])
    data = prog.compile()
    red = affine_cones(data)
    assert red.rows[0] is None and red.rows[1] is not None
    sol = prog.solve(affine_psd=True)
    assert sol.verified and sol.objective == pytest.approx(1.0, abs=1e-6)


def test_affine_psd_is_refused_outside_the_direct_back_end():
    prog, *_ = _lmi_program()
    with pytest.raises(sd.InputError, match="direct Clarabel back end.*Try: backend='direct'"):
        prog.solve(backend="cvxpy", affine_psd=True)


def test_reweighted_family_matches_a_fresh_build():
    """set_weights re-uses the Gram layout and the check's structure; rows and structure equal
    those of a family built with the new weights from scratch."""
    def family(weights):
        prog = sd.SOSProgram("family")
        a = prog.new_var()
        T1 = PolyMatrix([[X**2 + 1, X], [X, 1 + 0 * X]])
        T2 = PolyMatrix([[a * 1.0 + 0 * X, 0 * X], [0 * X, a * 1.0 + 0 * X]])
        con = prog.add_sos_matrix_family([T1, T2], weights)
        prog.minimize(a)
        return prog, con

    prog, con = family([1.0, 1.0])
    first = prog.solve()
    s1 = constraint_gram_structure(con, con.poly.exps)
    con.set_weights([2.0, 0.5])
    again = prog.solve()
    fresh_prog, fresh = family([2.0, 0.5])
    ref = fresh_prog.solve()
    assert first.verified and again.verified and ref.verified
    assert np.array_equal(con.rows.rows, fresh.rows.rows) and np.allclose(con.rows.vals, fresh.rows.vals)
    assert np.allclose(con.rows.rhs, fresh.rows.rhs)
    assert constraint_gram_structure(con, con.poly.exps) is s1          # remembered across weights
    direct = gram_structure(fresh.poly.exps, fresh.basis.exps)
    assert np.array_equal(s1.pair_at, direct.pair_at) and np.array_equal(s1.p_at, direct.p_at)
    assert again.objective == pytest.approx(ref.objective, abs=1e-7)

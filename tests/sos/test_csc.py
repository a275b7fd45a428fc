"""sosdyn.sos.csc: CSC matrices from canonical arrays, equal to scipy's own constructions."""
import numpy as np
import pytest
import scipy.sparse as sp

from sosdyn.sos import csc as C


@pytest.mark.parametrize("fast", [True, False])
def test_triplets_and_vstack_match_scipy(fast, monkeypatch):
    monkeypatch.setattr(C, "_FAST", fast and C._FAST)
    rng = np.random.default_rng(0)
    cells = rng.choice(5 * 7, size=12, replace=False)
    r, c, v = cells // 7, cells % 7, rng.normal(size=12)
    M = C.from_triplets(r, c, v, (5, 7))
    ref = sp.csc_matrix((v, (r, c)), shape=(5, 7))
    assert isinstance(M, sp.csc_matrix) and M.shape == (5, 7) and M.nnz == 12
    np.testing.assert_array_equal(M.toarray(), ref.toarray())
    assert M.indices.dtype == np.int32 and M.has_sorted_indices
    E = C.csc(np.zeros(0), np.zeros(0, np.int64), np.zeros(8, np.int64), (0, 7))     # no rows
    S = C.vstack([(M, 1), (E, -1), (ref, -1), (M, 1)], 7)
    want = sp.vstack([ref, -ref, ref]).toarray()
    np.testing.assert_array_equal(S.toarray(), want)
    # the same matrix: the product may differ by summation order only (scipy versions differ)
    np.testing.assert_allclose(S @ np.arange(7.0), want @ np.arange(7.0), rtol=1e-14, atol=1e-14)
    assert C.vstack([(M, 1), (E, 1)], 7) is M                  # one block with rows: itself


def test_wrapping_is_checked_at_import():
    assert C._wrapping_works() is C._FAST is True              # scipy here accepts the wrapping


def test_coarse_memory_bound_is_above_the_estimate():
    import sosdyn as sd
    from sosdyn.sos import examples
    from sosdyn.sos.backends import coarse_bytes, solver_bytes
    x, y = sd.variables("x y")
    p1 = sd.SOSProgram()
    p1.add_sos(x**4 + y**4 + x**2 * y**2 + 1)
    p2 = sd.SOSProgram()
    p2.add_sos((x**2 + y**2 + 1) ** 3, cone="sdsos")
    for prog in (p1, p2, examples.chebyshev()[0], examples.probability_bound()[0], examples.moore_greitzer(0.77)):
        data = prog.compile()
        estimate = solver_bytes(data, "CLARABEL", "direct")
        assert estimate <= coarse_bytes(data) < 10 * estimate

"""ICAStep: every iterate is certified and the cost does not increase."""
import numpy as np
import pytest

from sosdyn.lfd.fit.contraction import contraction_degree, field_exponents, margin_matrix, metric_exponents, state_variables
from sosdyn.lfd.fit.steps import DynamicsStep, ICAStep, LeastSquaresData
from sosdyn.poly import PolyMatrix, Polynomial, jacobian, monomial_values
from sosdyn.sos import matrix_form
from sosdyn.sos.conic import affine_cones

A = np.array([[-1.0, 4.0], [0.0, -1.0]])


def test_ica_iterates_stay_certified_and_lower_the_cost():
    Z = np.random.default_rng(0).uniform(-1, 1, size=(200, 2))
    data = LeastSquaresData(np.ones((200, 1)), Z, Z @ A.T)
    fexps, vars = field_exponents(2, 1), state_variables(2)
    C, _ = DynamicsStep(data, fexps, metric_exponents(2, 0), vars, 0.1, 1e-4).solve(np.eye(2)[:, :, None])
    ica = ICAStep(data, fexps, vars, gamma=0.1, margin=1e-4, eps=1e-3)
    P, costs = np.eye(2), [data.cost(C)]
    for _ in range(4):
        C, P, sol = ica.solve(C, P)
        costs.append(data.cost(C))
        G = C[0].T @ P + P @ C[0] + 0.1 * P
        assert sol.usable and np.isclose(np.trace(P), 2.0)
        assert np.linalg.eigvals(np.linalg.solve(P, G)).real.max() < 0
    assert all(b <= a + 1e-9 for a, b in zip(costs, costs[1:])) and costs[-1] < 0.5 * costs[0]
    names = ica.tables[0].names
    assert names[:3] == ("own", "margin", ("P0", (0, 0))) and names[-2:] == ("1/a", "a")


def test_ica_family_is_the_schur_matrix_at_the_iterate():
    """sum_t w_t T_t at (C0, P0, a) equals [[-(L + gamma P) - delta g I, dJ^T, dP], [dJ, I/a, 0],
    [dP, 0, a I]] built entry by entry (cubic fields: J0 depends on z), for component 1, whose
    terms are component 0's with the ids renamed."""
    n, gamma, margin, alpha = 2, 0.1, 1e-3, 0.7
    rng = np.random.default_rng(1)
    Z = rng.uniform(-1, 1, size=(50, n))
    fexps, vars = field_exponents(n, 3), state_variables(n)
    data = LeastSquaresData(np.full((50, 2), 0.5), monomial_values(Z, fexps), Z)
    ica = ICAStep(data, fexps, vars, gamma=gamma, margin=margin, eps=1e-3)
    C0 = rng.normal(size=data.shape)
    P0 = np.array([[1.2, 0.3], [0.3, 0.8]])
    table, con = ica.tables[1], ica.cons[1]
    con.set_weights(table.weights(ica.weights(C0[1].ravel(), P0, alpha)))

    lin = fexps.sum(axis=1) == 1
    ids = ica.ids.reshape(2, n, -1)[1]
    Jd = jacobian([Polynomial(vars, fexps[lin], np.hstack([np.zeros((n, 1)), np.eye(n)]), ids[i])
                   for i in range(n)], vars)
    J0 = jacobian([Polynomial(vars, fexps, C0[1, i]) for i in range(n)], vars)
    J0l = C0[1][:, lin] @ fexps[lin]
    P, I = ica.P, PolyMatrix.identity(n)
    grow = margin_matrix(vars, n, contraction_degree(0, 3))
    A00 = -(Jd.T @ P0 + P0 @ Jd) - (J0.T @ P + P @ J0) + (J0l.T @ P0 + P0 @ J0l) - gamma * P - margin * grow
    A10, A20 = Jd - J0l, P - P0
    Z0 = PolyMatrix(np.zeros((n, n)))
    M = PolyMatrix(np.block([[A00.entries, A10.T.entries, A20.T.entries],
                             [A10.entries, (I * (1 / alpha)).entries, Z0.entries],
                             [A20.entries, Z0.entries, (I * alpha).entries]]))
    q, _ = matrix_form(M, with_basis=False)
    assert q.vars == con.poly.vars
    diff = con.poly - q
    assert np.abs(diff.coef).max(initial=0.0) < 1e-12 and np.abs(q.coef).max() > 0.5


def test_ica_term_count_is_quadratic_in_n():
    """One "J0 P0" term per entry of the symmetric J0^T P0 + P0 J0 (not one per (c, ab)), and
    one term per weight: the parts weighted by P0_ab (or by C0_c) are one term."""
    n = 4
    Z = np.random.default_rng(2).uniform(-1, 1, size=(50, n))
    fexps, vars = field_exponents(n, 1), state_variables(n)
    ica = ICAStep(LeastSquaresData(np.ones((50, 1)), Z, Z), fexps, vars, gamma=0.1, margin=1e-4, eps=1e-3)
    pairs, units = n * (n + 1) // 2, n * n
    # own, margin, P0 (J P0 and P0), J0 (J0 P and J0), J0 P0, 1/a, a
    assert len(ica.tables[0].names) == 2 + pairs + units + pairs + 2 == 40


def test_ica_step_with_affine_cones_is_the_same_program():
    """The ICA step hands its constant Gram blocks to Clarabel as cones on their expressions
    (affine_psd): the same optimum as the plain lowering, and every block still checked."""
    Z = np.random.default_rng(0).uniform(-1, 1, size=(200, 2))
    data = LeastSquaresData(np.ones((200, 1)), Z, Z @ A.T)
    fexps, vars = field_exponents(2, 1), state_variables(2)
    C, _ = DynamicsStep(data, fexps, metric_exponents(2, 0), vars, 0.1, 1e-4).solve(np.eye(2)[:, :, None])
    ica = ICAStep(data, fexps, vars, gamma=0.1, margin=1e-4, eps=1e-3)
    _, _, sol = ica.solve(C, np.eye(2))
    plain = ica.prog.solve()
    assert sol.verified and plain.verified
    assert sol.objective == pytest.approx(plain.objective, rel=1e-6, abs=1e-9)
    assert len(sol.verify().checks) == len(plain.verify().checks) >= 4
    assert sum(rows is not None for rows in affine_cones(sol.data).rows) == 2    # ica[0], P - eps I

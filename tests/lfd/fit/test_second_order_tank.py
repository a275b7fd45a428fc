"""The tracking field and the energy tank of the second-order model: closed forms, the theorem's
inequality under adversarial nominal fields, the tank a known demo needs (scipy quadrature), and a
system built with a known quadratic V whose demos need no tank."""
import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.linalg import solve_continuous_lyapunov
from scipy.special import softmax

from sosdyn.lfd.fit.second_order.core import companion, lmi, nominal_fields
from sosdyn.lfd.fit.second_order.tank import (TANK_RATE, TankField, check_tank, energy_rates, tank_filter,
                                              tank_metric, tank_needs)
from sosdyn.lfd.fit.second_order.tracking import GOAL_RADIUS, kernel_widths, tracking_accelerations


def fade(E):
    return 1.0 - np.exp(-(E ** 2).sum(axis=1) / (2 * GOAL_RADIUS ** 2))


def test_tracking_field_of_one_sample_is_its_critically_damped_pull():
    rng = np.random.default_rng(0)
    S, Sa = rng.normal(size=(1, 4)), rng.normal(size=(1, 2))
    E = np.vstack([rng.normal(size=(5, 4)), np.zeros((1, 4)), np.full((1, 4), 0.01)])
    w = 2.5
    want = fade(E)[:, None] * (Sa + w ** 2 * S[:, :2] + 2 * w * S[:, 2:]) - w ** 2 * E[:, :2] - 2 * w * E[:, 2:]
    assert np.allclose(tracking_accelerations(E, S, Sa, kernel_widths(2, 0.1, 0.5), w), want, atol=1e-12)
    assert np.array_equal(tracking_accelerations(np.zeros((1, 4)), S, Sa, kernel_widths(2, 0.1, 0.5), w), [[0, 0]])


def test_tracking_field_is_the_kernel_average_of_the_pulls():
    rng = np.random.default_rng(1)
    S, Sa, E = rng.normal(size=(30, 4)), rng.normal(size=(30, 2)), rng.normal(size=(300, 4))
    D, w = kernel_widths(2, 0.7, 1.3), 1.5
    W = softmax(-0.5 * (((E[:, None, :] - S[None]) * D) ** 2).sum(-1), axis=1)
    targets = Sa + w ** 2 * S[:, :2] + 2 * w * S[:, 2:]
    want = fade(E)[:, None] * (W @ targets) - w ** 2 * E[:, :2] - 2 * w * E[:, 2:]
    assert np.allclose(tracking_accelerations(E, S, Sa, D, w), want, atol=1e-10)
    # far from every sample (weights that underflow in a plain softmax) the nearest sample's pull
    far = S[3] + np.array([0.0, 0.0, 40.0, 0.0])
    A = tracking_accelerations(far[None], S, Sa, kernel_widths(2, 0.01, 0.01), w)
    assert np.isfinite(A).all()


def certified_pair(gamma=0.2, omega=2.0):
    """A witness C_0 (critically damped at omega) and a metric M from the Lyapunov equation
    F^T M + M F + 2 gamma M = -I (scipy), so L = -I < 0."""
    C0 = nominal_fields(2, 1, omega)
    F = companion(C0)[0]
    M = solve_continuous_lyapunov((F + gamma * np.eye(4)).T, -np.eye(4))
    return C0[0], 0.5 * (M + M.T)


def test_filter_keeps_the_tank_theorem_for_any_nominal_field():
    gamma = 0.2
    C0, M = certified_pair(gamma)
    assert np.linalg.eigvalsh(lmi(companion(C0[None])[0], M, gamma)).max() < 0
    rng = np.random.default_rng(2)
    E = rng.normal(scale=3.0, size=(5000, 4))
    A = rng.normal(scale=1e3, size=(5000, 2))                    # adversarial nominal accelerations
    V = np.einsum("ti,ij,tj->t", E, M, E)
    b = np.where(rng.random(5000) < 0.3, 0.0, rng.uniform(0, 5, 5000) * V)
    out, bdot = tank_filter(E, A, b, M, C0, gamma)
    _, dV = energy_rates(E, M, out)
    W = V + b
    assert np.all(dV + bdot + 2 * gamma * W <= 1e-9 * (W + np.abs(dV)))          # dW/dt' <= -2 gamma' W
    assert np.all(bdot + (TANK_RATE + 2 * gamma) * b >= -1e-9 * (W + np.abs(dV)))    # the tank stays >= 0
    # where the nominal field already obeys the allowed rate it is returned unchanged
    _, d1 = energy_rates(E, M, A)
    free = d1 <= -2 * gamma * V + TANK_RATE * b
    assert free.any() and (~free).any()
    assert np.array_equal(out[free], A[free])


def test_tank_need_of_a_known_demo_matches_quadrature():
    gamma, dt = 0.3, 1e-4
    t = np.arange(0.0, 8.0, dt)
    x, v, a = (1 + 2 * t) * np.exp(-t), (1 - 2 * t) * np.exp(-t), (2 * t - 3) * np.exp(-t)
    E, Edot = np.column_stack([x, v]), np.column_stack([v, a])
    M = np.eye(2)

    def u(s):                                   # V = x^2 + v^2, dV/dt = 2 x v + 2 v a
        xs, vs, acc = (1 + 2 * s) * np.exp(-s), (1 - 2 * s) * np.exp(-s), (2 * s - 3) * np.exp(-s)
        return np.exp(2 * gamma * s) * max(0.0, 2 * xs * vs + 2 * vs * acc + 2 * gamma * (xs ** 2 + vs ** 2))
    want = quad(u, 0.0, 8.0, limit=200, points=[0.5, 1.0, 1.5, 2.0])[0] / 2.0     # V(0) = x0^2 + v0^2 = 2
    got = tank_needs([(E, Edot)], M, gamma, dt)[0]
    assert want > 0.1 and got == pytest.approx(want, rel=1e-3)


def test_demos_of_a_system_with_a_known_quadratic_v_need_no_tank():
    gamma = 0.2
    C0, M_true = certified_pair(gamma)
    F = companion(C0[None])[0]
    dt = 0.01
    states = []
    for z0 in ([1.0, 0.5, 0.0, 0.0], [-0.8, 1.0, 0.3, 0.0], [0.2, -1.0, 0.0, -0.5]):
        sol = solve_ivp(lambda _, z: F @ z, (0, 6.0), z0, t_eval=np.arange(0, 6.0, dt), rtol=1e-10, atol=1e-12)
        E = sol.y.T
        states.append((E, E @ F.T))
    assert tank_needs(states, M_true, gamma, dt).max() == 0.0       # the known V: no demo ever needs the tank
    M = tank_metric(states, C0, gamma, dt, 1e-6, M_true)
    assert tank_needs(states, M, gamma, dt).max() < 1e-6
    assert np.linalg.eigvalsh(lmi(F, M, gamma)).max() < 0 and np.linalg.eigvalsh(M).min() > 0


def test_check_passes_a_tracking_model_and_refuses_a_forged_witness():
    gamma, T = 0.2, 1.0
    C0, M = certified_pair(gamma)
    rng = np.random.default_rng(3)
    field = TankField(rng.normal(size=(40, 4)), rng.normal(size=(40, 2)), kernel_widths(2, 0.3, 0.5), 3.0, M, C0,
                      gamma * T, 2.0)
    assert check_tank(field, gamma, 2000, 0).passed
    forged = TankField(*[getattr(field, k) for k in ("samples", "accelerations", "inv_widths", "omega", "M")],
                       C0 + np.hstack([np.zeros((2, 2)), 3.0 * np.eye(2)]), gamma * T, 2.0)   # B = +I: unstable
    report = check_tank(forged, gamma, 2000, 0)
    assert not report.passed and min(m if m is not None else -1 for m in report.proven_margins) <= 0

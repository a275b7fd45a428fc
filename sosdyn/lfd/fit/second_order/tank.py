"""A certified second-order model that may gain energy from a tank: the filter, the tank, its size.

Scaled units as :mod:`.core`: e = ((x - g)/s, v T/s), t' = t/T, gamma' = gamma T. The
certificate is a quadratic V(e) = e^T M e with a *witness* field a_0 = C_0 e,
F_0 = [[0, I], [C_0]], F_0^T M + M F_0 + 2 gamma' M < 0 (checked exactly, as every component of the
mixture model). Along (e_v, a) the energy changes at the rate

    dV/dt' = 2 (M e)_x . e_v + 2 (M e)_v . a          (affine in the acceleration a).

The state carries a tank b >= 0 (energy, the units of V). Given any nominal acceleration a*
(:mod:`.tracking`), the model's acceleration is a* if dV/dt'(a*) <= r(e, b) =
-2 gamma' V + rho b, else the point of the segment a_0 -> a* where dV/dt' = r(e, b)
(:func:`tank_filter`); the tank pays for what V gains above the certified decay and leaks:

    u = max(0, dV/dt' + 2 gamma' V) <= rho b,     db/dt' = -u - 2 gamma' b.

*Theorem* (docs/theory.md, "An energy tank"): W = V + b obeys dW/dt' <= -2 gamma' W and b stays
>= 0, whatever a* is; so V(t) <= e^{-2 gamma t} (V(0) + b(0)) and the position never leaves
|x - g| <= s sqrt((V(0) + b(0)) lambda_max((M^-1)_xx)). The tank lets a motion climb in V (a loop
away from the goal, a start near the goal that swings out) by at most b(0), which
:func:`tank_needs` sizes from the training demos: b(0) = beta V(e(0)).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sosdyn.poly import PolyMatrix, Polynomial
from sosdyn.sos import SOSProgram, svec_to_matrix
from sosdyn.sos.gram import matrix_to_svec
from ..certificate import check_sample_count
from ..steps import solve_with_fallback
from .certificate import SAMPLE_BOX, SecondOrderCertificate, certificate
from .core import METRIC_EPS, Scaled, companion, demo_derivatives, lmi, metric_step, nominal_fields
from .tracking import kernel_widths, tracking_accelerations, tracking_set

TANK_RATE = 50.0            # rho: the tank pays at most rho b per unit of t' (any rho > 0 keeps the theorem)
TANK_ROWS = 200             # samples per demo in the tank metric step
TANK_BOX = 2.0              # the sampled check draws tank levels b in [0, TANK_BOX beta V(e)]
#: M >= eps I in the tank metric step, eps = TANK_EPS x the mean V(start_d) (capped at the nominal metric's
#: smallest eigenvalue, so the nominal metric stays feasible): a floor that keeps M's condition at 16-64
#: on the crossing set, with excursion bounds 1.6-3.3x a test reproduction's largest distance to the goal
#: (1e-3: condition 64-4241, bounds 1.6-21x, tanks beta 0.2-40 instead of 0.6-40).
TANK_EPS = 0.1


@dataclass(frozen=True)
class TankField:
    """What a tracking model computes with, scaled units: the tracked samples S (N, 2n) and their
    accelerations Sa (N, n), the kernel's inverse widths (2n,) and pull rate w
    (:mod:`.tracking`), the metric M (2n, 2n), the witness C_0 (n, 2n), gamma' and the
    tank factor beta (b(0) = beta V(e(0)))."""

    samples: np.ndarray
    accelerations: np.ndarray
    inv_widths: np.ndarray
    omega: float
    M: np.ndarray
    C0: np.ndarray
    gamma: float
    beta: float


def energy_rates(E: np.ndarray, M: np.ndarray, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V, dV/dt') at the rows of E (m, 2n) with accelerations A (m, n)."""
    n = A.shape[1]
    ME = E @ M
    return np.einsum("ti,ti->t", ME, E), 2.0 * (np.einsum("ti,ti->t", ME[:, :n], E[:, n:])
                                               + np.einsum("ti,ti->t", ME[:, n:], A))


def tank_filter(E, A, b, M, C0, gamma):
    """The certified acceleration and the tank's rate (module docstring) at the rows of E (m, 2n)
    with nominal accelerations A (m, n) and tank levels b (m,): (accelerations (m, n), db/dt' (m,))."""
    A0 = E @ C0.T
    V, d1 = energy_rates(E, M, A)
    _, d0 = energy_rates(E, M, A0)
    allowed = -2.0 * gamma * V + TANK_RATE * np.maximum(b, 0.0)
    over = d1 > allowed
    lam = np.clip((allowed[over] - d0[over]) / (d1[over] - d0[over]), 0.0, 1.0)
    out = A.copy()
    out[over] = A0[over] + lam[:, None] * (A[over] - A0[over])
    _, d = energy_rates(E, M, out)
    return out, -np.maximum(0.0, d + 2.0 * gamma * V) - 2.0 * gamma * b


def demo_states(demos, scaled) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per demo, (E, dE/dt') in scaled units from one Savitzky-Golay fit (the training window)."""
    parts, _ = demo_derivatives(demos, scaled.window)
    s, T, g = scaled.length, scaled.time, scaled.goal
    out = []
    for pos, vel, acc in parts:
        E = np.hstack([(pos - g) / s, vel * T / s])
        out.append((E, np.hstack([E[:, pos.shape[1]:], acc * T * T / s])))
    return out


def need_terms(E, Edot, gamma, dt):
    """Per sample, the matrices S_t with tr(M S_t) = dV/dt' + 2 gamma' V, and the weights
    exp(2 gamma' t') dt' with which the tank needed from the first sample is sum_t w_t max(0, tr(M S_t))."""
    S = np.einsum("ti,tj->tij", E, Edot)
    S = S + S.transpose(0, 2, 1) + 2.0 * gamma * np.einsum("ti,tj->tij", E, E)
    return S, np.exp(2.0 * gamma * dt * np.arange(len(E))) * dt


def tank_needs(states, M, gamma, dt) -> np.ndarray:
    """beta_d = (tank the demo d needs from its first sample) / V(its first sample), per demo: the
    smallest b(0) / V(0) with which the tank never runs dry along it (b(t') = e^{-2 gamma' t'}
    (b(0) - int_0^t' e^{2 gamma' s} u ds) >= 0)."""
    out = []
    for E, Edot in states:
        S, w = need_terms(E, Edot, gamma, dt)
        u = np.maximum(0.0, np.einsum("ij,tij->t", M, S))
        out.append(float(w @ u) / float(E[0] @ M @ E[0]))
    return np.array(out)


def tank_metric(states, C0, gamma, dt, margin, M0, rel_eps=TANK_EPS, solver="CLARABEL") -> np.ndarray:
    """The metric that needs the least tank: minimise sum_d sum_t w_t max(0, tr(M S_t)) (the demos'
    tank needs, :func:`need_terms`) subject to sum_d V_d(first sample) = the same sum under ``M0`` (the
    scale of M), M >= eps I with eps = min(``rel_eps`` x that sum / the number of demos, lambda_min(M0))
    and -L(F_0, M) >= margin I (the witness stays a certificate). Linear in M; ``M0``, a metric of the
    witness with that margin, is feasible, so the program always is."""
    m = C0.shape[1]
    F0 = companion(C0[None])[0]
    scale = float(sum(E[0] @ M0 @ E[0] for E, _ in states))
    eps = min(rel_eps * scale / len(states), float(np.linalg.eigvalsh(M0)[0]))
    prog = SOSProgram("second-order tank metric")
    M = prog.new_psd(m, name="M")
    I = PolyMatrix.identity(m)
    prog.add_sos_matrix(M - I * eps, name="metric positive")
    prog.add_sos_matrix(-lmi(F0, M, gamma) - I * margin, name="witness")
    rows, weights, starts = [], [], []
    for E, Edot in states:
        keep = np.arange(0, len(E), max(1, -(-len(E) // TANK_ROWS)))
        S, w = need_terms(E, Edot, gamma, dt)
        rows.append(np.array([matrix_to_svec(St) for St in S[keep]]))
        weights.append(w[keep] * (len(E) / len(keep)))
        starts.append(matrix_to_svec(np.outer(E[0], E[0])))
    rows, weights = np.vstack(rows), np.concatenate(weights)
    prog.add_eq(Polynomial.affine(M.ids, np.sum(starts, axis=0)), scale, name="scale")
    slack = prog.new_ids(len(rows), name="needs")
    for t, (row, sid) in enumerate(zip(rows, slack)):
        prog.add_ge(Polynomial.affine([sid], [1.0]), 0.0, name=f"slack[{t}]")
        prog.add_ge(Polynomial.affine(np.concatenate([[sid], M.ids]), np.concatenate([[1.0], -row])), 0.0,
                    name=f"need[{t}]")
    prog.minimize(Polynomial.affine(slack, weights / weights.sum()))
    sol = solve_with_fallback(prog, solver, affine_psd=True)
    return svec_to_matrix(sol.values_of(M.ids), m)


def tank_dynamics(field: TankField, E: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(accelerations (m, n), db/dt' (m,)) at the rows of E with tank levels b: the tracking field
    filtered by the tank (module docstring)."""
    A = tracking_accelerations(E, field.samples, field.accelerations, field.inv_widths, field.omega)
    return tank_filter(E, A, b, field.M, field.C0, field.gamma)


def initial_tank(field: TankField, E: np.ndarray) -> np.ndarray:
    """b(0) = beta V(e(0)) at the rows of E."""
    return field.beta * np.einsum("ti,ij,tj->t", E, field.M, E)


def scaled_states(X, V, goal, length: float, time: float) -> np.ndarray:
    """e = ((x - g)/s, v T/s) at the rows of X and V (m, n)."""
    return np.hstack([(X - goal) / length, V * (time / length)])


def derivatives_at(field: TankField, X, V, goal, length: float, time: float, tank) -> tuple[np.ndarray, np.ndarray]:
    """In data units: (accelerations (m, n), db/dt per second (m,)) at positions X, velocities V and
    tank levels ``tank`` (m,) for the goal ``goal`` (:func:`tank_dynamics`; a = (s/T^2) a', db/dt = (db/dt') / T)."""
    A, bdot = tank_dynamics(field, scaled_states(X, V, goal, length, time), np.asarray(tank, dtype=float))
    return A * (length / time ** 2), bdot / time


def fit_tank_field(demos, scaled: Scaled, gamma: float, omega: float, widths: tuple[float, float], margin: float,
                   factor: float, solver="CLARABEL") -> tuple[TankField, np.ndarray]:
    """The tracking model of ``demos`` (``gamma`` = gamma', scaled): the samples it tracks, the witness
    C_0 of the critically damped system at rate max(w, 2 gamma') (:func:`~.core.nominal_fields`): with
    w the tracking rate it is the landings' field, so near the goal, where the tracked samples are
    landings, the tracking field is the witness and the filter leaves it alone;
    the metric needing the least tank under it (:func:`tank_metric`, margin min(``margin``, the
    nominal metric's)), and beta = ``factor`` x the largest need of a training demo. Returns the
    field and the demos' needs beta_d."""
    n = demos.dim
    S, Sa = tracking_set(demos, scaled, omega)
    C0 = nominal_fields(n, 1, max(omega, 2.0 * gamma))
    M0, t = metric_step(C0, gamma, solver=solver)
    states = demo_states(demos, scaled)
    M = tank_metric(states, C0[0], gamma, scaled.dt, min(margin, t), M0, TANK_EPS, solver)
    needs = tank_needs(states, M, gamma, scaled.dt)
    return TankField(S, Sa, kernel_widths(n, *widths), float(omega), M, C0[0], float(gamma),
                     float(factor * needs.max())), needs


def tank_summary(report: SecondOrderCertificate, beta: float, needs) -> list[str]:
    """Lines for people: the certificate of a tracking model, its tank and the training demos' needs."""
    lines = [f"metric M and the witness field's LMI proven in exact arithmetic (margin {min(report.proven_margins):.2e}); "
             f"V + tank decays at rate 2 gamma (max sampled rate {report.max_sampled_rate:.2e} over "
             f"{report.n_samples} states x 2 tank levels); tank b(0) = {beta:.3g} V(start)"]
    if needs is not None:
        lines.append(f"the training demonstrations need tanks of {min(needs):.3g}-{max(needs):.3g} V(start)")
    return lines


def check_tank(field: TankField, gamma: float, n_samples: int, seed: int) -> SecondOrderCertificate:
    """The independent check of a tracking model (``gamma`` in 1/s of the data): the metric and the
    witness's LMI proven in exact arithmetic (:func:`~.certificate.certificate`), then at
    ``n_samples`` states e in |e|_inf <= SAMPLE_BOX, each with an empty tank and with a random level
    in [0, TANK_BOX beta V(e)], the model's own acceleration and tank rate recomputed into
    (dW/dt' + 2 gamma' W) / W (W = V + b) and, for the tank to stay >= 0, -(db/dt' + (rho + 2 gamma') b) / W:
    the largest of them is the sampled rate (<= SAMPLED_TOL to pass)."""
    n_samples = check_sample_count(n_samples)
    rng = np.random.default_rng(seed)
    m = field.M.shape[0]
    E = rng.uniform(-SAMPLE_BOX, SAMPLE_BOX, size=(n_samples, m))
    V = np.einsum("ti,ij,tj->t", E, field.M, E)
    E2, V2 = np.vstack([E, E]), np.concatenate([V, V])
    b = np.concatenate([np.zeros(n_samples), rng.uniform(0.0, TANK_BOX * max(field.beta, 1.0), n_samples) * V])
    A, bdot = tank_dynamics(field, E2, b)
    _, dV = energy_rates(E2, field.M, A)
    W = V2 + b
    g = field.gamma
    rates = np.concatenate([(dV + bdot + 2.0 * g * W) / W, -(bdot + (TANK_RATE + 2.0 * g) * b) / W])
    return certificate(field.C0[None], field.M, gamma, g, float(rates.max()), n_samples)


__all__ = ["TANK_BOX", "TANK_RATE", "TankField", "check_tank", "demo_states", "energy_rates", "fit_tank_field",
           "derivatives_at", "initial_tank", "need_terms", "scaled_states", "tank_dynamics", "tank_filter", "tank_metric", "tank_needs",
           "tank_summary"]

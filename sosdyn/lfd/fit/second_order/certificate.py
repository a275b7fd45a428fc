"""The independent check of a second-order certificate, and what the certificate implies.

The model (scaled units, :mod:`.core`): de/dt' = sum_k h_k(e) F_k e with F_k = [[0, I],
[C_k]]. The certificate is the constant metric M; it is checked, not trusted:

1. **exact**: M and -L_k = -(F_k^T M + M F_k + 2 gamma' M) (k = 1..K) are formed in rational
   arithmetic from the stored floats (every float is a rational) and their smallest
   eigenvalues bounded from below by :func:`~sosdyn.sos.gram.proven_min_eig` (an exact LDL^T of
   an integer rounding); each bound must be > 0: a proof that M > 0 and L_k < 0;
2. **sampled**: at ``n_samples`` states e drawn in |e|_inf <= 2 (twice the data box), once with
   the model's own gating h(e) and once with random weights in the simplex, the decrease rate
   (dV/dt') / V + 2 gamma' (V = e^T M e) must be <= SAMPLED_TOL.

Consequences (docs/theory.md): V(e(t)) <= exp(-2 gamma' t') V(e(0)), so |x(t) - g| <= s sqrt(V(e(0))
lambda_max((M^-1)_xx)) for all t (:func:`excursion_bound`): the transient is bounded by a number
known at the start. What it forbids: the M-energy must fall at rate 2 gamma' along every solution,
so a demonstration along which V rises cannot be followed (:func:`energy_violations`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from fractions import Fraction

import numpy as np

from sosdyn.sos.gram import proven_min_eig
from ..certificate import check_sample_count
from ..gmm import PositionMixture
from .core import accelerations, companion

SAMPLED_TOL = 1e-8
SAMPLE_BOX = 2.0


@dataclass
class SecondOrderCertificate:
    """Both checks' numbers (scaled units; ``gamma`` in 1/s of the data, ``gamma_scaled`` = gamma T).

    ``lmi_max_eigs[k]``: the largest eigenvalue of L_k (float); ``proven_margins[k]``: a proven
    lower bound on the smallest eigenvalue of -L_k (None: not proven); ``metric_min_eig``: a proven
    lower bound on the smallest eigenvalue of M; ``max_sampled_rate``: the largest sampled
    (dV/dt')/V + 2 gamma'; ``passed`` only if every proven bound is > 0 and the sampled rate
    is <= SAMPLED_TOL."""

    M: np.ndarray
    gamma: float
    gamma_scaled: float
    lmi_max_eigs: list
    proven_margins: list
    metric_min_eig: float | None
    max_sampled_rate: float
    n_samples: int
    passed: bool

    def as_dict(self) -> dict:
        out = asdict(self)
        out["M"] = self.M.tolist()
        return out

    def __str__(self) -> str:
        worst = min((m if m is not None else -np.inf) for m in self.proven_margins)
        return (f"second-order certificate: gamma {self.gamma:.3g}/s, {len(self.proven_margins)} LMIs, "
                f"max eigenvalue of L_k {max(self.lmi_max_eigs):.3e}, proven min margin {worst:.3e}, "
                f"proven min eig M {self.metric_min_eig if self.metric_min_eig is not None else float('nan'):.3e}; "
                f"sampled ({self.n_samples} states x 2 gatings or tank levels): max rate {self.max_sampled_rate:.3e} "
                f"-> {'PASSED' if self.passed else 'FAILED'}")


def exact_matrix(A) -> np.ndarray:
    """The float matrix A as an object array of exact Fractions."""
    return np.vectorize(lambda v: Fraction(float(v)), otypes=[object])(np.asarray(A, dtype=float))


def exact_lmis(C, M, gamma_scaled) -> list[np.ndarray]:
    """-L_k = -(F_k^T M + M F_k + 2 gamma' M) for every k, in exact rational arithmetic."""
    Mq = exact_matrix(0.5 * (M + M.T))
    g2 = 2 * Fraction(float(gamma_scaled))
    out = []
    for F in companion(C):
        Fq = exact_matrix(F)
        X = Fq.T.dot(Mq)
        out.append(-(X + X.T + g2 * Mq))
    return out


def sampled_rates(C, M, gamma_scaled, H, E) -> np.ndarray:
    """(dV/dt')/V + 2 gamma' at the rows of E (N, 2n) with gating weights H (N, K)."""
    n = C.shape[1]
    Edot = np.hstack([E[:, n:], accelerations(C, H, E)])
    V = np.einsum("ti,ij,tj->t", E, M, E)
    return 2.0 * np.einsum("ti,ij,tj->t", E, M, Edot) / V + 2.0 * gamma_scaled


def exact_part(C, M, gamma_scaled) -> tuple[list, list, float | None]:
    """Check 1 of the module docstring: (largest eigenvalue of each L_k (float), proven lower bounds
    on the smallest eigenvalue of each -L_k, proven lower bound on that of M)."""
    negL = exact_lmis(C, M, gamma_scaled)
    maxeig = [float(-np.linalg.eigvalsh(Q.astype(float))[0]) for Q in negL]
    return maxeig, [proven_min_eig(Q) for Q in negL], proven_min_eig(exact_matrix(0.5 * (M + M.T)))


def certificate(C, M, gamma, gamma_scaled, worst_rate: float, n_samples: int) -> SecondOrderCertificate:
    """The certificate of the fields C (their LMIs proven exactly) and a sampled worst rate: passed
    only if every proven bound is > 0 and the rate is finite and <= SAMPLED_TOL."""
    maxeig, proven, metric = exact_part(C, M, gamma_scaled)
    passed = (all(p is not None and p > 0 for p in proven) and metric is not None and metric > 0
              and np.isfinite(worst_rate) and worst_rate <= SAMPLED_TOL)
    return SecondOrderCertificate(M, float(gamma), gamma_scaled, maxeig, proven, metric, float(worst_rate),
                                  n_samples, bool(passed))


def check_second_order(C, M, gamma, time_scale, mixture: PositionMixture, n_samples: int,
                       seed: int) -> SecondOrderCertificate:
    """Both checks of the module docstring for the fields C (K, n, 2n) and metric M (scaled units)."""
    n_samples = check_sample_count(n_samples)
    C, M = np.asarray(C, dtype=float), np.asarray(M, dtype=float)
    g = float(gamma) * float(time_scale)
    rng = np.random.default_rng(seed)
    K, n = C.shape[:2]
    E = rng.uniform(-SAMPLE_BOX, SAMPLE_BOX, size=(n_samples, 2 * n))
    rates = np.concatenate([sampled_rates(C, M, g, mixture.responsibilities(E), E),
                            sampled_rates(C, M, g, rng.dirichlet(np.ones(K), size=n_samples), E)])
    return certificate(C, M, gamma, g, float(rates.max()), n_samples)


def excursion_bound(M, e0) -> float:
    """max |e_x| over the ellipsoid {e : e^T M e <= e0^T M e0}: sqrt(V0 lambda_max((M^-1)_xx)).
    A certified solution from e0 never leaves it (scaled units: multiply by s for the data's)."""
    M = np.asarray(M, dtype=float)
    n = M.shape[0] // 2
    V0 = float(e0 @ M @ e0)
    Px = np.linalg.inv(M)[:n, :n]
    return float(np.sqrt(V0 * np.linalg.eigvalsh(0.5 * (Px + Px.T))[-1]))


def energy_violations(M, gamma_scaled, E, Edot, floor=1e-9) -> dict:
    """Along demonstration samples e (rows of E) with derivatives Edot = (e_v, e_a): the fraction
    where the demo itself breaks the certified decrease (dV/dt' > -2 gamma' V) and where it gains
    M-energy (dV/dt' > 0). Samples with V <= floor x max V (at the goal) are not counted."""
    V = np.einsum("ti,ij,tj->t", E, M, E)
    dV = 2.0 * np.einsum("ti,ij,tj->t", E, M, Edot)
    live = V > floor * V.max()
    return {"samples": int(live.sum()),
            "slower_than_certified": float(np.mean(dV[live] > -2.0 * gamma_scaled * V[live])),
            "energy_gain": float(np.mean(dV[live] > 0.0))}


def mixture_summary(report: SecondOrderCertificate, violations: dict | None) -> list[str]:
    """A mixture's certificate for people: its exact LMIs and sampled decrease, and (``violations``,
    :func:`energy_violations`) how often the training demonstrations break the certified decrease."""
    worst = min((m if m is not None else -np.inf) for m in report.proven_margins)
    lines = [f"metric M and {len(report.proven_margins)} LMIs proven in exact arithmetic (min margin {worst:.2e}), "
             f"max sampled decrease rate {report.max_sampled_rate:.2e} over {report.n_samples} states x 2 gatings"]
    if violations:
        lines.append(f"the demonstrations decay slower than certified at {violations['slower_than_certified']:.0%} "
                     f"of {violations['samples']} samples and gain M-energy at {violations['energy_gain']:.0%}")
    return lines

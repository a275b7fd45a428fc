"""Evidence that a learned CDSP model contracts: its SOS certificate, checked independently.

The certificate: M(z) - eps I and -G_k(z) (k = 1..K) are SOS matrices
(:func:`~sosdyn.lfd.fit.contraction.certificate_matrices`, the one builder of these matrices,
used by :func:`certify` to solve for it and by :func:`check_certificate` to check it).
Two checks, neither reusing the solver's matching matrices:

1. Gram check -- the polynomials y^T (M - eps I) y and y^T (-G_k) y are rebuilt from the
   model's own coefficients (C, W) and compared with z^T Q z for the stored Gram matrices Q;
   Q must be PSD (min eigenvalue) and the coefficient residual tiny.
2. Sampled check -- at DEFAULT_SAMPLES = 10^4 states (or as many as asked, within
   [MIN_SAMPLES, MAX_SAMPLES]) drawn in twice the data box (|z|_inf <= 2), the largest
   generalised eigenvalue of (G_k(z), M(z)) over k must be <= 0 and M(z) > 0.

The Gram check is the proof; the sampled check is an independent sanity check of it. Loading a
model file always runs both with DEFAULT_SAMPLES states, whatever the file's parameters say.

Why the paper's polynomial metric adds nothing for linear sub-systems: with f_k = A_k z,
dM(z)[A_k z] vanishes at z = 0, so evaluating (4) at z = 0 gives
A_k^T M(0) + M(0) A_k + gamma M(0) <= 0 -- the constant metric M(0) certifies every A_k
that M(z) certifies. :func:`collapse_diagnostic` measures it on a learned model.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from numbers import Integral

import numpy as np

from sosdyn.errors import InputError
from sosdyn.limits import check_bytes
from sosdyn.sos import SOSProgram, check_gram, matrix_form
from .contraction import certificate_matrices, constant_index, degree, sample_states, sampled_eigenvalues

SAMPLED_TOL = 1e-8
COLLAPSE_TOL, COLLAPSE_SAMPLES = 1e-7, 2000
DEFAULT_SAMPLES, MIN_SAMPLES, MAX_SAMPLES = 10_000, 100, 10**6   # states of the sampled check


def check_sample_count(value, name: str = "n_samples") -> int:
    """``value`` as the number of states of the sampled check; InputError outside the range."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Integral) \
            or not MIN_SAMPLES <= value <= MAX_SAMPLES:
        raise InputError(f"{name} must be an integer in [{MIN_SAMPLES}, {MAX_SAMPLES}] (states of the "
                         f"sampled certificate check), got {value!r}. Try: the default {DEFAULT_SAMPLES}.")
    return int(value)


@dataclass
class CertificateReport:
    """Numbers of both checks; ``passed`` only if every one holds."""

    solver_status: str
    min_gram_eig: float
    max_coeff_residual: float
    max_sampled_eig: float
    min_metric_eig: float
    n_samples: int
    passed: bool
    checks: list = field(default_factory=list)
    warp: dict | None = None        # a warped model's map check (:func:`~sosdyn.lfd.fit.composite.check`)

    def as_dict(self) -> dict:
        return asdict(self)

    def __str__(self) -> str:
        w = self.warp
        return (f"certificate ({self.solver_status}): min Gram eigenvalue {self.min_gram_eig:.3e}, "
                f"max coefficient residual {self.max_coeff_residual:.2e}; sampled ({self.n_samples} "
                f"states): max generalised eigenvalue {self.max_sampled_eig:.3e}, min eig M "
                f"{self.min_metric_eig:.3e}" + ("" if w is None else
                f"; warp: {w['n_maps']} maps, max Lipschitz number {w['max_lipschitz']:.4f} (< 1)" +
                ("" if "twist_shear" not in w else f", twist of shear bound K = {w['twist_shear']:.4g}") +
                f", sampled min singular value of J_phi {w['min_singular']:.3e} >= bound {w['singular_bound']:.3e}") +
                f" -> {'PASSED' if self.passed else 'FAILED'}")


def certify(C, fexps, W, mexps, gamma, eps, solver="CLARABEL"):
    """Solve for the certificate of numeric (C, W): M - eps I and -G_k SOS matrices.

    Returns the Solution (its program's constraints carry the Gram matrices)."""
    prog = SOSProgram("certificate")
    for name, P in certificate_matrices(C, fexps, W, mexps, gamma, eps):
        prog.add_sos_matrix(P, name=name)
    return prog.solve(solver=solver)


def extract_certificate(solution, eps: float) -> dict:
    """Plain-data certificate (bases and Gram matrices) of a certification Solution.

    The solver's numbers are taken as they are (``checked=False``): :func:`check_certificate`
    is the independent check that decides whether they certify the model."""
    cons = []
    for con in solution.program.sos_constraints:
        finite = np.isfinite(solution.x).all()
        Q = con.gram_matrix(solution, checked=False) if finite else np.full((len(con.basis),) * 2, np.nan)
        cons.append({"name": con.name, "vars": list(con.basis.vars), "basis": con.basis.exps.tolist(),
                     "gram": Q.tolist()})
    return {"status": solution.status, "eps": eps, "constraints": cons}


def check_certificate(C, fexps, W, mexps, gamma, certificate: dict, n_samples: int,
                      seed: int) -> CertificateReport:
    """Both checks of ``certificate`` (as :func:`extract_certificate` returns it) for the model
    (C, W, gamma); the sampled one at ``n_samples`` states drawn with ``seed``."""
    n_samples = check_sample_count(n_samples)
    K, n = C.shape[:2]
    m = C.shape[2] + W.shape[2]
    # G, J, M repeated, J^T M, its transpose, dM[f], the whitened S: ~8 (K, n, n) blocks per state
    check_bytes(8.0 * n_samples * (8 * K * n * n + n**3 + 2 * n * m), "the sampled certificate check",
                "fewer samples (n_samples)")
    checks = []
    mats = certificate_matrices(C, fexps, W, mexps, gamma, certificate["eps"])
    if len(mats) == len(certificate["constraints"]):
        for (_, P), c in zip(mats, certificate["constraints"]):
            q, _ = matrix_form(P)
            vars = tuple(c["vars"])
            basis = np.asarray(c["basis"], dtype=np.int64).reshape(-1, len(vars))
            Q = np.asarray(c["gram"], dtype=float)
            if not np.isfinite(Q).all():
                continue
            checks.append(check_gram(c["name"], "sos_matrix", q.with_vars(vars), basis, Q))
    complete = len(checks) == len(mats)
    max_g, min_m = sampled_eigenvalues(C, fexps, W, mexps, sample_states(seed, n_samples, n), gamma)
    passed = (complete and all(c.passed for c in checks) and max_g <= SAMPLED_TOL and min_m > 0
              and certificate["status"] in ("optimal", "optimal_inaccurate"))
    return CertificateReport(
        certificate["status"], min((c.min_eig for c in checks), default=np.nan),
        max((c.residual for c in checks), default=np.nan), max_g, min_m, int(n_samples), bool(passed),
        [asdict(c) for c in checks])


def collapse_diagnostic(C, fexps, W, mexps, gamma, seed: int) -> dict | None:
    """Does the constant part M(0) of the metric certify the same fields? (module docstring).

    None for a constant metric; else the largest generalised eigenvalue of (G_k, M(0)) at
    COLLAPSE_SAMPLES states drawn with ``seed``, and whether it is <= COLLAPSE_TOL."""
    if degree(mexps) == 0:
        return None
    const = constant_index(mexps)
    Zs = sample_states(seed, COLLAPSE_SAMPLES, W.shape[0])
    worst, _ = sampled_eigenvalues(C, fexps, W[:, :, const:const + 1], mexps[const:const + 1], Zs, gamma)
    holds = worst <= COLLAPSE_TOL
    linear = degree(fexps) == 1
    return {"constant_metric_certifies": bool(holds), "max_eig_with_constant_metric": worst,
            "field_degree": degree(fexps),
            "note": ("collapse: M(0) alone certifies the learned fields, as it must for linear "
                     "sub-systems (dM[A z] = 0 at z = 0)") if holds and linear else
                    ("the state-dependent metric is needed: M(0) alone does not certify the fields"
                     if not holds else "M(0) alone also certifies these fields")}

"""Evidence that a learned CDSP model contracts: its SOS certificate, checked independently.

Two checks, neither reusing the solver's matching matrices:

1. Gram check -- the polynomials y^T (M - eps I) y and y^T (-G_k) y are rebuilt from the
   model's own coefficients (C, W) and compared with z^T Q z for the stored Gram matrices Q;
   Q must be PSD (min eigenvalue) and the coefficient residual tiny.
2. Sampled check -- at DEFAULT_SAMPLES = 10^4 states (or as many as asked, within
   [MIN_SAMPLES, MAX_SAMPLES]) drawn in twice the data box (|z|_inf <= 2), the largest
   generalised eigenvalue of (G_k(z), M(z)) over k must be <= 0 and M(z) > 0.

The Gram check is the proof; the sampled check is an independent sanity check of it. Loading a
model file always runs both with DEFAULT_SAMPLES states, whatever the file's parameters say.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from numbers import Integral

import numpy as np

from ..errors import InputError
from ..limits import check_bytes
from ..poly import PolyMatrix
from ..sos import SOSProgram
from ..sos.solution import check_gram
from .fields import (contraction_matrices, contraction_polymatrix, eval_metric, generalized_max_eig,
                     numeric_fields, numeric_metric)

SAMPLED_TOL = 1e-8
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

    def as_dict(self) -> dict:
        return asdict(self)

    def __str__(self) -> str:
        return (f"certificate ({self.solver_status}): min Gram eigenvalue {self.min_gram_eig:.3e}, "
                f"max coefficient residual {self.max_coeff_residual:.2e}; sampled ({self.n_samples} "
                f"states): max generalised eigenvalue {self.max_sampled_eig:.3e}, min eig M "
                f"{self.min_metric_eig:.3e} -> {'PASSED' if self.passed else 'FAILED'}")


def extract_certificate(solution, eps: float) -> dict:
    """Plain-data certificate (bases and Gram matrices) of a certification Solution.

    The solver's numbers are taken as they are (``checked=False``): :func:`check_model` is the
    independent check that decides whether they certify the model."""
    cons = []
    for con in solution.program.sos_constraints:
        finite = np.isfinite(solution.x).all()
        Q = con.gram_matrix(solution, checked=False) if finite else np.full((len(con.basis),) * 2, np.nan)
        cons.append({"name": con.name, "vars": list(con.basis.vars), "basis": con.basis.exps.tolist(),
                     "gram": Q.tolist()})
    return {"status": solution.status, "eps": eps, "constraints": cons}


def certificate_matrices(model):
    """The polynomial matrices the certificate is about, in its order: M - eps I, -G_1..-G_K."""
    vars, n = model._vars, model.dim_
    M = numeric_metric(model.W_, model.metric_exps_, vars)
    mats = [M - model.certificate_["eps"] * PolyMatrix.identity(n)]
    mats += [-contraction_polymatrix(f, M, vars, model.gamma)
             for f in numeric_fields(model.C_, model.field_exps_, vars)]
    return mats


def check_model(model, n_samples: int, seed: int) -> CertificateReport:
    """Both checks on ``model``; the sampled one at ``n_samples`` states drawn with ``seed``."""
    n_samples = check_sample_count(n_samples)
    K, n = model.C_.shape[:2]
    m = model.C_.shape[2] + model.W_.shape[2]
    # G, J, M repeated, J^T M, its transpose, dM[f], the whitened S: ~8 (K, n, n) blocks per state
    check_bytes(8.0 * n_samples * (8 * K * n * n + n**3 + 2 * n * m), "the sampled certificate check",
                "fewer samples (n_samples)")
    cert = model.certificate_
    checks = []
    mats = certificate_matrices(model)
    if len(mats) == len(cert["constraints"]):
        for P, c in zip(mats, cert["constraints"]):
            q, _ = SOSProgram._matrix_form(P)
            vars = tuple(c["vars"])
            basis = np.asarray(c["basis"], dtype=np.int64).reshape(-1, len(vars))
            Q = np.asarray(c["gram"], dtype=float)
            if not np.isfinite(Q).all():
                continue
            checks.append(check_gram(c["name"], "sos_matrix", q.with_vars(vars), basis, Q))
    complete = len(checks) == len(mats)
    Zs = np.random.default_rng(seed).uniform(-2.0, 2.0, size=(int(n_samples), model.dim_))
    G = contraction_matrices(model.C_, model.field_exps_, model.W_, model.metric_exps_, Zs, model.gamma)
    M = eval_metric(model.W_, model.metric_exps_, Zs)
    min_m = float(np.linalg.eigvalsh(M)[:, 0].min())
    max_g = float(generalized_max_eig(G, M).max()) if min_m > 0 else np.inf
    passed = (complete and all(c.passed for c in checks) and max_g <= SAMPLED_TOL and min_m > 0
              and cert["status"] in ("optimal", "optimal_inaccurate"))
    return CertificateReport(
        cert["status"], min((c.min_eig for c in checks), default=np.nan),
        max((c.residual for c in checks), default=np.nan), max_g, min_m, int(n_samples), bool(passed),
        [asdict(c) for c in checks])

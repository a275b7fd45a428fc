"""Certify, extract, check and the collapse diagnostic, on arrays with known answers."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.fit.certificate import (DEFAULT_SAMPLES, certify, check_certificate, check_sample_count,
                                    collapse_diagnostic, extract_certificate)
from sosdyn.lfd.fit.contraction import constant_index, field_exponents, metric_exponents

FEXPS, MEXPS = field_exponents(2, 1), metric_exponents(2, 0)
A = np.array([[-1.0, 4.0], [0.0, -1.0]])        # contracts in P below, not in the identity
P = np.array([[1.0, 1.0], [1.0, 9.0]])


@pytest.fixture(scope="module")
def certificate():
    return extract_certificate(certify(A[None], FEXPS, P[:, :, None], MEXPS, 0.1, 5e-4), 5e-4)


def test_a_true_certificate_is_extracted_and_passes_both_checks(certificate):
    assert certificate["status"] == "optimal" and certificate["eps"] == 5e-4
    assert [c["name"] for c in certificate["constraints"]] == ["M - eps I", "-G[0]"]
    report = check_certificate(A[None], FEXPS, P[:, :, None], MEXPS, 0.1, certificate, 500, 0)
    assert report.passed and report.min_gram_eig >= -1e-9 and report.max_coeff_residual < 1e-7
    # G = A^T P + P A + 0.1 P: its largest generalised eigenvalue against P, at every state
    G = A.T @ P + P @ A + 0.1 * P
    expected = np.linalg.eigvals(np.linalg.solve(P, G)).real.max()
    assert np.isclose(report.max_sampled_eig, expected, atol=1e-12)
    assert np.isclose(report.min_metric_eig, np.linalg.eigvalsh(P)[0])


def test_the_same_certificate_for_other_coefficients_fails(certificate):
    report = check_certificate(-A[None], FEXPS, P[:, :, None], MEXPS, 0.1, certificate, 500, 0)
    assert not report.passed and report.max_sampled_eig > 1.0 and report.max_coeff_residual > 1.0
    identity = check_certificate(A[None], FEXPS, np.eye(2)[:, :, None], MEXPS, 0.1, certificate, 500, 0)
    assert not identity.passed and identity.max_sampled_eig > 0   # A + A^T has eigenvalue +2


def test_collapse_diagnostic_on_a_polynomial_metric_with_linear_fields():
    mexps = metric_exponents(2, 2)
    W = np.zeros((2, 2, mexps.shape[0]))
    W[:, :, constant_index(mexps)] = np.eye(2)
    W[0, 0, np.flatnonzero(mexps[:, 0] == 2)[0]] = 0.3               # M = I + 0.3 z1^2 e1 e1^T
    diag = collapse_diagnostic(-np.eye(2)[None], FEXPS, W, mexps, 0.5, seed=0)
    assert diag["constant_metric_certifies"] is True and diag["field_degree"] == 1
    assert np.isclose(diag["max_eig_with_constant_metric"], -1.5)       # f = -z, M(0) = I: gamma - 2
    assert diag["note"].startswith("collapse")
    assert collapse_diagnostic(-np.eye(2)[None], FEXPS, np.eye(2)[:, :, None], MEXPS, 0.5, seed=0) is None


def test_sample_count_bounds():
    assert check_sample_count(DEFAULT_SAMPLES) == 10_000 and check_sample_count(np.int64(100)) == 100
    for bad in (99, 10**6 + 1, True, 1e4):
        with pytest.raises(sd.InputError, match=r"n_samples must be an integer in \[100, 1000000\]"):
            check_sample_count(bad)

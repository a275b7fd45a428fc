"""Bounded warps (issue 23, item 3): at most MAX_MAPS bumps, and prod_j (1 - l_j) >= MIN_CONDITION,
whether the warp is fitted, checked or loaded from a file."""
import json

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.lfd.fit import composite
from sosdyn.lfd.fit.warp import LIP_FACTOR, MAX_MAPS, MIN_CONDITION, check_maps, fit_maps, jacobian, lipschitz_numbers
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.fileformat import _digest
from sosdyn.lfd.model.files import load_model


def bump(lip, n=2, sigma=0.5):
    """One bump at (0.3, 0, ...) with Lipschitz number ``lip``."""
    v = np.zeros(n)
    v[0] = lip * sigma / LIP_FACTOR
    c = np.zeros(n)
    c[0] = 0.3
    return c[None], v[None], np.array([sigma])


@pytest.mark.parametrize("lip", [1 - 2e-16, 1 - 1e-13])
def test_a_near_singular_bump_is_refused(lip):
    C, V, S = bump(lip)
    with pytest.raises(InputError, match="Lipschitz number .* >= 1|below 1e-12, so J_phi may be near singular"):
        check_maps(C, V, S, np.zeros(2))


def test_the_floor_is_on_the_product():
    """Forty bumps of l = 0.5 each: every one invertible, together prod = 2^-40 = 9.1e-13 < 1e-12."""
    C, V, S = (np.repeat(a, 40, axis=0) for a in bump(0.5))
    check_maps(C[:39], V[:39], S[:39], np.zeros(2))                    # 2^-39 = 1.8e-12: accepted
    with pytest.raises(InputError, match=r"= 9.09e-13 is below 1e-12"):
        check_maps(C, V, S, np.zeros(2))


def test_too_many_bumps_are_refused():
    C, V, S = (np.repeat(a, MAX_MAPS + 1, axis=0) for a in bump(1e-6))
    with pytest.raises(InputError, match="10001 maps, more than 10000"):
        check_maps(C, V, S, np.zeros(2))


def test_fit_maps_stops_above_the_floor():
    """With l_max = 0.9 every bump may take 1 - l_j = 0.1: the fit stops after 11 (prod 1e-11), where
    a 12th could reach 1e-12 (without the floor it would go on: the mismatch is far from matched)."""
    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 2))
    Y = X + 2 * rng.normal(size=(200, 2))
    C, V, S = fit_maps(X, Y, np.zeros(2), n_maps=500, l_max=0.9, beta=1.0, scale=3.0)
    cond = np.prod(1 - lipschitz_numbers(V, S))
    assert len(S) == 11 and MIN_CONDITION <= cond < MIN_CONDITION / 0.1
    check_maps(C, V, S, np.zeros(2))


@pytest.fixture(scope="module")
def model_file(linear_demos, tmp_path_factory):
    path = tmp_path_factory.mktemp("warp") / "m.json"
    CDSP(n_components=1, warp="none").fit(linear_demos).save(path)
    return path


def _forge(path, out, maps):
    data = json.loads(path.read_text())
    data["state"]["warp_"] = {"centers": maps[0].tolist(), "vectors": maps[1].tolist(), "sigmas": maps[2].tolist()}
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})      # checksum recomputed
    out.write_text(json.dumps(data))
    return out


def test_a_forged_near_singular_warp_does_not_load(model_file, tmp_path):
    path = _forge(model_file, tmp_path / "near.json", bump(1 - 1e-13))
    with pytest.raises(ModelFileError, match="invalid state.warp_: prod_j .* below 1e-12.* Try: fewer maps"):
        load_model(path)


def test_a_forged_huge_warp_is_refused_before_any_work(model_file, tmp_path, monkeypatch):
    """40,000 tiny bumps took 21-44 s to load (J_phi at 10^4 states per bump); now refused before the
    load-time check of J_phi starts. Counted: a legal one-bump warp goes through that check (the spy is
    on the path), the huge one never reaches it."""
    calls = []
    real = composite.bump_jacobian
    monkeypatch.setattr(composite, "bump_jacobian", lambda *a, **k: calls.append(len(a[3])) or real(*a, **k))
    load_model(_forge(model_file, tmp_path / "one.json", bump(0.5)))
    assert calls == [1]
    maps = tuple(np.repeat(a, 40_000, axis=0) for a in bump(1e-6))
    path = _forge(model_file, tmp_path / "huge.json", maps)
    with pytest.raises(ModelFileError, match="invalid state.warp_: 40000 maps, more than 10000"):
        load_model(path)
    assert calls == [1]


def _plain_jacobian(X, C, V, S, goal):
    """The reference: J <- (I + v grad rho^T) J at every row, for every bump."""
    U = np.array(X, dtype=float)
    J = np.broadcast_to(np.eye(U.shape[1]), (U.shape[0],) + (U.shape[1],) * 2).copy()
    for c, v, s in zip(C, V, S):
        rho = np.exp(-np.sum((U - c) ** 2, axis=-1) / s ** 2)
        grad = (-2.0 / s ** 2) * rho[:, None] * (U - c)
        J += v[None, :, None] * np.einsum("ki,kij->kj", grad, J)[:, None, :]
        U += (rho - np.exp(-np.sum((goal - c) ** 2) / s ** 2))[:, None] * v
    return U, J


@pytest.mark.parametrize("n, sigma", [(2, 0.5), (2, 0.02), (3, 1e-3), (7, 0.7)])
def test_the_jacobian_is_the_plain_chain_rule_bit_for_bit(n, sigma):
    rng = np.random.default_rng(n)
    C, Z = rng.uniform(-2, 2, (60, n)), rng.uniform(-2, 2, (500, n))
    V = rng.normal(size=(60, n)) * 0.1 * sigma
    U, J = jacobian(Z, C, V, np.full(60, sigma), np.zeros(n))
    U0, J0 = _plain_jacobian(Z, C, V, np.full(60, sigma), np.zeros(n))
    assert np.array_equal(U, U0) and np.array_equal(J, J0)


def _legal_warp(m, sigma, seed=0, n=2):
    """m bumps of l_j = 2.7e-3 (prod (1 - l_j) = 1.8e-12 for m = MAX_MAPS, above the floor)."""
    rng = np.random.default_rng(seed)
    C, V = rng.uniform(-2, 2, (m, n)), rng.normal(size=(m, n))
    V *= (2.7e-3 * sigma / LIP_FACTOR / np.linalg.norm(V, axis=1))[:, None]
    return C, V, np.full(m, sigma)


def test_tiny_bumps_cost_only_the_rows_they_move(monkeypatch):
    """A maximal warp of tiny bumps (the forged-file case): J_phi is updated only where a bump is
    not exactly 0 in float (|z - c| < sqrt(745) sigma = 0.027: 1.4e-4 of the box), so the 10^4 bumps
    update about 1.4 states each out of 10^4 (the plain loop: all 10^8; 14-37 s to load such a
    file, now 1.4 s: timing in problems/bench/predict.py)."""
    counted = []
    einsum = np.einsum
    monkeypatch.setattr(np, "einsum", lambda *a, **k: counted.append(a[-1].shape[-1]) or einsum(*a, **k))
    C, V, S = _legal_warp(MAX_MAPS, 1e-3)
    Z = np.random.default_rng(1).uniform(-2, 2, (10_000, 2))
    U, J = jacobian(Z, C, V, S, np.zeros(2))
    assert len(counted) == MAX_MAPS and sum(counted) < 30_000            # rows updated, over all bumps
    sv = np.linalg.svd(J, compute_uv=False)
    assert sv.min() >= np.prod(1 - lipschitz_numbers(V, S)) and np.abs(sv - 1).max() < 0.01


@pytest.mark.slow
def test_a_maximal_forged_warp_loads_and_a_bad_bump_in_it_does_not(model_file, tmp_path):
    C, V, S = _legal_warp(MAX_MAPS, 0.5)
    loaded = load_model(_forge(model_file, tmp_path / "max.json", (C, V, S)))
    assert loaded.verification_.warp["n_maps"] == MAX_MAPS and loaded.verification_.warp["passed"]
    V[-1] *= 1.5 / 2.7e-3                                              # the last bump: l = 1.5
    with pytest.raises(ModelFileError, match="invalid state.warp_: map 9999 has Lipschitz number 1.5 >= 1"):
        load_model(_forge(model_file, tmp_path / "bad.json", (C, V, S)))

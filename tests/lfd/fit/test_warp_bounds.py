"""Bounded warps (issue 23, item 3): at most MAX_MAPS bumps, and prod_j (1 - l_j) >= MIN_CONDITION,
whether the warp is fitted, checked or loaded from a file."""
import json
import time

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.lfd.fit.warp import LIP_FACTOR, MAX_MAPS, MIN_CONDITION, check_maps, fit_maps, lipschitz_numbers
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


def test_a_forged_huge_warp_is_refused_before_any_work(model_file, tmp_path):
    """40,000 tiny bumps took 21-44 s to load (J_phi at 10^4 states per bump); now refused at once."""
    maps = tuple(np.repeat(a, 40_000, axis=0) for a in bump(1e-6))
    path = _forge(model_file, tmp_path / "huge.json", maps)
    t0 = time.perf_counter()
    with pytest.raises(ModelFileError, match="invalid state.warp_: 40000 maps, more than 10000"):
        load_model(path)
    assert time.perf_counter() - t0 < 5.0

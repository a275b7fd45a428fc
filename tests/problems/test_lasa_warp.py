"""problems.lasa_warp: the diffeomorphic pre-warp variants of the ds-opt LASA run and their cache keys."""
import pytest

import sosdyn as sd
from problems import lasa_corrective, lasa_dsopt, lasa_warp
from sosdyn.errors import SosdynError
from sosdyn.lfd.fit.warp import AUTO_WARPS, WARP_DEFAULTS


def test_warp_variants_are_registered_cdsp_settings():
    assert set(lasa_warp.VARIANTS) <= set(lasa_dsopt.VARIANTS)
    assert set(lasa_warp.SELECTIONS) <= set(lasa_dsopt.SELECTIONS)
    for candidates in lasa_warp.SELECTIONS.values():
        assert set(candidates) <= set(lasa_dsopt.VARIANTS)
    model = sd.CDSP(**lasa_dsopt.settings("CDSP plain warped 60 d1", 3, False))
    assert model.warp == dict(WARP_DEFAULTS, n_maps=60, decay=1.0) == AUTO_WARPS["60 maps, decay 1"]
    assert (model.corrective_rounds, model.random_state) == (0, 3)
    assert sd.CDSP(**lasa_dsopt.settings("CDSP warped", 0, False)).corrective_rounds == 3
    # the selection's warped candidates are CDSP()'s radial warp="auto" candidates (the default before issue 36)
    chosen = [lasa_dsopt.VARIANTS[v].get("warp") for v in lasa_warp.SELECTIONS["CDSP warped selected"]]
    assert chosen == ["none", AUTO_WARPS["60 maps, decay 0.75"], AUTO_WARPS["60 maps, decay 1"]]


def test_cache_keys():
    """A variant without a warp keeps its key; a warp's settings and the key version are part of its key."""
    plain = lasa_dsopt.settings("CDSP plain", 0, False)
    assert lasa_warp.key_extra(plain) == {} and "warp" not in lasa_corrective.key_params(plain)
    warped = lasa_dsopt.settings("CDSP plain warped", 0, False)
    assert lasa_warp.key_extra(warped) == {"warp_key_version": lasa_warp.WARP_KEY_VERSION}
    assert lasa_corrective.key_params(warped)["warp"] == WARP_DEFAULTS
    assert lasa_corrective.key_params(warped) != lasa_corrective.key_params(
        lasa_dsopt.settings("CDSP plain warped 60 d1", 0, False))


def test_a_warped_job_on_line(tmp_path):
    try:
        sd.load_lasa("Line")
    except SosdynError as exc:
        pytest.skip(str(exc))
    entry = lasa_dsopt.run_job("Line", "CDSP plain warped", 0, False, tmp_path, False)
    assert entry["error"] is None and entry["certified"]
    assert entry["dtwd_test_mean"] < 400          # measured 294 (the plain fit's 294: Line needs no warp)

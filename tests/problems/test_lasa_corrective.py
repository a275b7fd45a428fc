"""problems.lasa_corrective: the corrective variants of the ds-opt LASA run and their cache keys."""
import sosdyn as sd
from problems import lasa_corrective, lasa_dsopt


def test_corrective_variants_are_registered_cdsp_settings():
    assert set(lasa_corrective.VARIANTS) <= set(lasa_dsopt.VARIANTS)
    assert lasa_dsopt.SELECTIONS["CDSP corrective selected"] == tuple(lasa_corrective.VARIANTS)
    assert lasa_dsopt.VARIANTS["CDSP default"] == {}                   # CDSP() itself: warp="auto" since issue 12
    plain = sd.CDSP(**lasa_dsopt.VARIANTS["CDSP plain"])
    assert (plain.corrective_rounds, plain.warp) == (0, "none")     # the default's core alone
    for name, kwargs in lasa_corrective.VARIANTS.items():           # "refitted twice", no warp, as registered
        assert (sd.CDSP(**kwargs).corrective_rounds, sd.CDSP(**kwargs).warp) == (2, "none"), name
    # the plain selections choose among plain fits, as before corrective refits were the default
    for selection in ("CDSP selected", "CDSP selected+cubic"):
        for v in lasa_dsopt.SELECTIONS[selection]:
            m = sd.CDSP(**lasa_dsopt.VARIANTS[v])
            assert (m.corrective_rounds, m.warp) == (0, "none"), (selection, v)


def test_a_plain_fit_keeps_its_cache_key():
    """At 0 rounds the corrective parameters are unused and left out of the key; so is warp="none"."""
    plain = lasa_corrective.key_params({"corrective_rounds": 0, "gamma": 0.02, "warp": "none"})
    assert plain["gamma"] == 0.02 and not any(k.startswith("corrective_") or k == "warp" for k in plain)
    corrective = lasa_corrective.key_params({"gamma": 0.02, "corrective_rounds": 3, "warp": "none"})
    assert (corrective["corrective_rounds"], corrective["corrective_tau"]) == (3, 0.5) and "warp" not in corrective
    assert lasa_corrective.key_params({})["warp"] == "auto"          # the default's key names its warp

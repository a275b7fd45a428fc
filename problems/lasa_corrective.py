"""Corrective-data variants of the ds-opt LASA run (problems.lasa_dsopt): CDSP with
``corrective_rounds`` refits on its own training rollouts' departures (sosdyn.lfd.fit.corrective; the
round kept by the rollouts' nearest-point deviation from demos 1-4, training data only).

"CDSP corrective" is ICA, K = 8 (the default's core) with 2 rounds and no warp, the others
the same rounds around two other linear configurations; "CDSP corrective selected" picks per shape
among the three by the protocol's training-reproduction DTWD.
"""
from __future__ import annotations

import sosdyn as sd
from sosdyn.lfd.fit.params import PRESETS

ROUNDS = {"corrective_rounds": 2, "warp": "none"}       # no warp: the variants as measured before it existed

VARIANTS = {
    "CDSP corrective": dict(ROUNDS),
    "CDSP-ICA K10 corrective": dict(PRESETS["ica"], n_components=10, **ROUNDS),
    "CDSP g0.02 corrective": dict(gamma=0.02, **ROUNDS),
}
#: Training-DTWD selection among the three. gamma = 0.02 with the default K = 8 rather than the preset
#: "ica"'s K = 6 of "CDSP-ICA g0.02": its corrective 26-shape TRAINING mean is lower (1102 vs 1191 mm).
SELECTIONS = {"CDSP corrective selected": tuple(VARIANTS)}


def key_params(kwargs: dict) -> dict:
    """Every CDSP parameter, defaults resolved: the cache key's settings. A plain fit's key omits the
    corrective parameters (unused at 0 rounds) and a fit without a warp omits ``warp``, so each is the
    key it had before those parameters existed."""
    params = sd.CDSP(**kwargs).get_params()
    if params["corrective_rounds"] == 0:
        params = {k: v for k, v in params.items() if not k.startswith("corrective_")}
    if params["warp"] == "none":
        params.pop("warp")
    return params

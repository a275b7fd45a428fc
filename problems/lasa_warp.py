"""Diffeomorphic pre-warp variants of the ds-opt LASA run (problems.lasa_dsopt): ``CDSP(warp=settings)``,
a CDSP fitted in coordinates u = phi(z) (sosdyn.lfd.warp), phi a composition of Gaussian bumps that
pulls the mean training demonstration onto a path along which |u| never increases.

Hyper-parameters from the TRAINING demos only (random_state 0, no corrective rounds, 26 shapes; numbers
in notes/acc_variants.md): of n_maps 15 / 30 / 60 / 100, "mean" / "each" curves and decay 0 / 0.25 /
0.5 / 0.75 / 1, 100 maps with decay 0.75 had the lowest training-reproduction DTWD (the warp's
defaults, sosdyn.lfd.warp.WARP_DEFAULTS, "CDSP plain warped"); among the selections {plain fit, warp A,
warp B} the lowest training mean is plain + 60 maps decay 0.75 + 60 maps decay 1 ("CDSP warped
selected"; these two warps are CDSP()'s warp="auto" candidates, sosdyn.lfd.warp.AUTO_WARPS, chosen there
by the rollouts' deviation rather than the protocol's DTWD).

A variant with a warp dict carries ``WARP_KEY_VERSION`` in its cache key (:func:`key_extra`): entries
computed by the former separate estimator (the warp in data coordinates) are not reused.
"""
from __future__ import annotations

from sosdyn.lfd.params import PLAIN
from sosdyn.lfd.warp import AUTO_WARPS, WARP_DEFAULTS

WARP_KEY_VERSION = 2            # 2: the warp inside CDSP, in its normalised coordinates z
D075, D1 = AUTO_WARPS.values()

VARIANTS = {
    "CDSP warped": {"warp": dict(WARP_DEFAULTS), "corrective_rounds": 3},
    "CDSP plain warped": dict(PLAIN, warp=dict(WARP_DEFAULTS)),
    "CDSP plain warped 60 d0.75": dict(PLAIN, warp=dict(D075)),
    "CDSP plain warped 60 d1": dict(PLAIN, warp=dict(D1)),
}
#: Per shape, the lowest training-reproduction DTWD of the plain fit and two warps ("CDSP plain" is
#: problems.lasa_dsopt's plain-fit variant): CDSP()'s candidates under the protocol's own rule.
SELECTIONS = {"CDSP warped selected": ("CDSP plain", "CDSP plain warped 60 d0.75", "CDSP plain warped 60 d1")}


def key_extra(kwargs: dict) -> dict:
    """What a variant's cache key adds to its CDSP parameters: the warp's key version for a warp dict."""
    return {"warp_key_version": WARP_KEY_VERSION} if isinstance(kwargs.get("warp"), dict) else {}

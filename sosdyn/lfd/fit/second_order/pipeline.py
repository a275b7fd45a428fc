"""The fit path of the second-order model (as :mod:`sosdyn.lfd.fit.pipeline` is the first order's):
checked demonstrations and the parameters of :class:`~sosdyn.lfd.model.second_order.SecondOrderCDSP`
in, its learned state out, for either field:

* ``"tracking"``: the samples scaled (:func:`~.core.scaled_samples`, one component), the kernel tracking
  field filtered by its energy tank (:func:`~.tank.fit_tank_field`) and the tank's independent check
  (:func:`~.tank.check_tank`); the witness C_0 is the one row of C;
* ``"mixture"``: the samples scaled, the gating GMM on e (:func:`~.core.fit_gating`), the fields and the
  metric (:func:`~.learner.fit_second_order`) and their independent check
  (:func:`~.certificate.check_second_order`).

A check that fails is a NotCertifiedError: no model is returned. :func:`check_field` is the same
check again, for a model's ``verify`` and a loaded file.
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import NotCertifiedError
from ...data.demonstrations import sample_step
from .certificate import check_second_order, energy_violations
from .core import fit_gating, scaled_samples
from .learner import fit_second_order
from .tank import check_tank, fit_tank_field


def fit(demos, params: dict, seed: int, progress=None) -> dict:
    """The learned attributes of a SecondOrderCDSP (``seed_`` .. ``energy_violations_``; ``tank_needs_``
    for the tracking field) fitted to the checked ``demos`` with ``params`` (its ``get_params()``) and the
    integer ``seed``; ``progress`` is called with each history row of the mixture's fit loop."""
    p = params
    if p["field"] == "tracking":
        scaled = scaled_samples(demos, 1, p["max_samples"])
        tank, needs = fit_tank_field(demos, scaled, float(p["gamma"]) * scaled.time, float(p["tracking_rate"]),
                                     (float(p["position_width"]), float(p["velocity_width"])), float(p["margin"]),
                                     float(p["tank_factor"]), p["solver"])
        report = check_tank(tank, p["gamma"], p["verify_samples"], seed)
        mixture, C, margin, history, chosen = None, tank.C0[None], -max(report.lmi_max_eigs), [], 0
    else:
        K = 1 if p["n_components"] == "bic" else int(p["n_components"])
        scaled = scaled_samples(demos, K, p["max_samples"])
        mixture, tank, needs = fit_gating(scaled.E, p["n_components"], seed), None, None
        result = fit_second_order(scaled, mixture, float(p["gamma"]), float(p["margin"]), int(p["max_iter"]),
                                  float(p["tol"]), float(p["metric_prox"]), p["solver_method"], p["solver"], progress,
                                  tracking=(int(p["tracking_copies"]), float(p["tracking_sigma"]),
                                            float(p["tracking_rate"]), seed))
        report = check_second_order(result.C, result.M, p["gamma"], scaled.time, mixture, p["verify_samples"], seed)
        C, margin, history, chosen = result.C, result.margin, result.history, result.chosen
    if not report.passed:
        raise NotCertifiedError(f"the second-order certificate failed its independent check: {report}",
                                status="not_certified", hint="a smaller gamma or a larger margin")
    n = demos.dim
    return {"seed_": seed, "dim_": n, "goal_": scaled.goal, "dt_": sample_step(demos), "units_": demos.units,
            "columns_": demos.columns, "length_scale_": scaled.length, "time_scale_": scaled.time,
            "window_": scaled.window, "mixture_": mixture, "tank_": tank, "C_": C, "M_": report.M, "margin_": margin,
            "verification_": report, "certified_": True, "history_": history, "chosen_iter_": chosen,
            **({"tank_needs_": needs} if tank is not None else {}),
            "energy_violations_": energy_violations(report.M, report.gamma_scaled, scaled.E,
                                                    np.hstack([scaled.E[:, n:], scaled.Ea]))}


def check_field(tank, mixture, C, M, gamma, time_scale, n_samples: int, seed: int):
    """The independent check of a fitted field: the tank's (:func:`~.tank.check_tank`) for the tracking
    field (``tank`` not None), else the mixture's (:func:`~.certificate.check_second_order`)."""
    if tank is not None:
        return check_tank(tank, gamma, n_samples, seed)
    return check_second_order(C, M, gamma, time_scale, mixture, n_samples, seed)

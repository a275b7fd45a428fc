"""Fitting the second-order model (:class:`~sosdyn.lfd.model.second_order.SecondOrderCDSP`): functions
on arrays, named as the first-order fit's parts in :mod:`sosdyn.lfd.fit`.

``core`` (scaled samples, the gating, the companion matrices and the LMI, the field and metric
steps, training rollouts: the model's equations), ``learner`` (the joint ICA step and the fit loop,
:func:`fit_second_order`), ``certificate`` (the independent check: exact LMIs and sampled decrease,
and what the certificate implies: the excursion bound), ``tracking`` and ``tank`` (the tracking field
under its energy tank), ``params`` (the parameters' names and checks) and ``pipeline`` (the fit path of
either field, :func:`~.pipeline.fit`).
"""
from .certificate import SecondOrderCertificate, check_second_order, energy_violations, excursion_bound
from .core import Scaled, acceleration_at, fit_gating, scaled_samples
from .learner import METHODS, SecondOrderFit, fit_second_order

__all__ = ["METHODS", "Scaled", "SecondOrderCertificate", "SecondOrderFit", "acceleration_at", "check_second_order",
           "energy_violations", "excursion_bound", "fit_gating", "fit_second_order", "scaled_samples"]

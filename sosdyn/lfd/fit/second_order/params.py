"""The second-order model's parameters (as :mod:`sosdyn.lfd.fit.params` holds the first order's): their
names, which of them apply to which field, and their checks, made before any optimisation (InputError
saying what to try); a model file's parameters go through the same checks.
"""
from __future__ import annotations

from collections.abc import Mapping
from numbers import Integral

import numpy as np

from sosdyn.errors import InputError
from ...rollout.events import is_positive_number
from ..params import check_params as check_first_order, check_solver
from .learner import METHODS

PARAMS = ("n_components", "gamma", "margin", "max_iter", "tol", "metric_prox", "solver_method", "tracking_copies",
          "tracking_sigma", "tracking_rate", "max_samples", "random_state", "verify_samples", "solver", "field",
          "position_width", "velocity_width", "tank_factor")
FIELDS = ("tracking", "mixture")
TRACKING_PARAMS = ("field", "position_width", "velocity_width", "tank_factor")
MIXTURE_PARAMS = ("n_components", "max_iter", "tol", "metric_prox", "solver_method", "tracking_copies",
                  "tracking_sigma")
#: The parameters of one field only, {name: ("field", that field)} (``MotionModel.only_with``).
ONLY_WITH = {**{k: ("field", "mixture") for k in MIXTURE_PARAMS},
             **{k: ("field", "tracking") for k in TRACKING_PARAMS[1:]}}
MAX_COPIES = 20                 # perturbed copies per sample (each multiplies the data term's rows)
POSITIVE = ("tracking_sigma", "tracking_rate", "position_width", "velocity_width", "tank_factor")


def check_params(p: Mapping, defaults: Mapping, first_order_defaults: Mapping) -> None:
    """Types and ranges of the parameters ``p`` (all of PARAMS), InputError suggesting ``defaults``: the
    first-order checks of the parameters both families have (:func:`sosdyn.lfd.fit.params.check_params`,
    the others from ``first_order_defaults``; ``solver_method`` is checked here: "energy" is ours alone),
    the solver, then the second order's own, a parameter of the other field set to anything but its default
    included."""
    shared = {k: v for k, v in p.items() if k != "solver_method"}
    check_first_order({**first_order_defaults, **shared}, {**first_order_defaults, **defaults})
    check_solver(p["solver"])
    if not isinstance(p["solver_method"], str) or p["solver_method"] not in METHODS:
        raise InputError(f"solver_method must be one of {METHODS}, got {p['solver_method']!r:.40}. Try: the "
                         "default, solver_method='ica'.")
    c = p["tracking_copies"]
    if isinstance(c, (bool, np.bool_)) or not isinstance(c, Integral) or not 0 <= c <= MAX_COPIES:
        raise InputError(f"tracking_copies must be an integer in [0, {MAX_COPIES}], got {c!r}. Try: the default, 2.")
    if not isinstance(p["field"], str) or p["field"] not in FIELDS:
        raise InputError(f"field must be one of {FIELDS}, got {p['field']!r:.40}. Try: the default, field='tracking'.")
    other = [k for k, (_, owner) in ONLY_WITH.items() if owner != p["field"]
             and not (p[k] is defaults[k] or p[k] == defaults[k])]
    if other:
        owner = ONLY_WITH[other[0]][1]
        raise InputError(f"{other[0]} applies to field='{owner}' only, not to field={p['field']!r}. Try: "
                         f"field='{owner}', or drop {other[0]}.")
    for name in POSITIVE:
        if not is_positive_number(p[name]):
            raise InputError(f"{name} must be a finite number > 0, got {p[name]!r}. Try: the default, {defaults[name]}.")

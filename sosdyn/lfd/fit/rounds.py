"""Fits made of several CDSP fits: corrective rounds, and the choice of warp (``warp="auto"``).

Corrective rounds take a function that makes one certified fit (raising NotCertifiedError
otherwise), the warp choice the candidates' fits (:func:`~.pipeline.candidate_fits`); both keep,
among the certified fits, the one whose reproductions of the TRAINING demonstrations deviate least
from them (:func:`~.corrective.training_score`; lower is better). A fitted model here is anything
with ``field(X, goal)``, ``goal_``, ``scale_``, ``certified_`` and ``history_``.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np

from sosdyn.errors import InputError, NotCertifiedError, SolverError
from .corrective import (
    MAX_PAIRS,
    TAU,
    MIN_PAIRS,
    augmented,
    corrective_demonstration,
    corrective_pairs,
    demo_scores,
    thin,
    training_rollouts,
    training_score,
)
from ..data.demonstrations import Demonstrations, sample_step


def corrective_fits(fit_round: Callable, demos: Demonstrations, n_rounds: int, tau: float, min_dist: float):
    """Rounds 0..n_rounds (:mod:`.corrective`): ``fit_round(r, data)`` fits round r on the
    demonstrations plus the corrective pseudo-demonstrations of rounds < r; round r's training
    rollouts give the pairs of round r + 1 (states farther than ``min_dist`` x round 0's scale from
    the demos). ``tau`` must be at least the data's sample step dt (InputError before any fit: a
    pull-back faster than one step makes labels of |p - x| / tau that Euler with step dt overshoots).
    Stops after a refit (r > 0) that is not certified or fails (a SolverError such as an infeasible
    or unbounded step, or a ValueError; a warning says which, and the rounds so far compete), a
    diverged rollout or fewer than MIN_PAIRS pairs. Returns (kept round, its model, every round's
    score, pairs per round, every round's history rows tagged with ``round``)."""
    goal, dt = np.asarray(demos.goal, dtype=float), sample_step(demos)
    if n_rounds and not tau >= dt:
        raise InputError(f"corrective_tau = {tau:.6g} s is shorter than the demonstrations' sample step "
                         f"{dt:.6g} s: the corrective labels v + (p - x) / tau would pull back faster than "
                         f"one step. Try: corrective_tau >= {dt:.3g} (the default is {TAU}), or "
                         "corrective_rounds=0.")
    P, V = demos.stacked()
    models, extra, history, scores, pairs = [], [], [], [], []
    for r in range(n_rounds + 1):
        try:
            model = fit_round(r, augmented(demos, extra))
        except (SolverError, ValueError) as exc:
            if r == 0:
                raise
            if not isinstance(exc, NotCertifiedError):
                warnings.warn(f"corrective round {r} failed ({type(exc).__name__}: {exc}); keeping the best "
                              f"of rounds 0..{r - 1}, all certified.", stacklevel=2)
            break                       # an uncertified or failed refit: the certified rounds so far compete
        models.append(model)
        history += [dict(row, round=r) for row in model.history_]
        reps = training_rollouts(lambda X, m=model: m.field(X, m.goal_), demos)
        scores.append(training_score(reps, demos))
        if r == n_rounds or reps is None:
            break
        X, Xdot = thin(*corrective_pairs(np.vstack(reps), P, V, tau, min_dist * models[0].scale_), MAX_PAIRS)
        pairs.append(len(X))
        if len(X) < MIN_PAIRS:
            break
        extra.append(corrective_demonstration(X, Xdot, goal, dt, f"corrective round {r + 1}"))
    kept = min(range(len(models)), key=lambda i: (not models[i].certified_, scores[i]))
    return kept, models[kept], scores, pairs, history


def warp_choice(fits: dict, demos: Demonstrations, block_field: Callable):
    """The kept fit among ``fits`` {name: fit, or None for a warped candidate that did not certify
    (score inf)}: the distinct fits (a candidate may share an earlier one's fit) scored together by
    :func:`~.corrective.demo_scores` on ``block_field(distinct fits)``, the certified one of lowest
    score kept. Returns (the kept fit, {name: score}); ties: the first candidate."""
    distinct = [f for i, f in enumerate(fits.values()) if f is not None and
                all(f is not g for g in list(fits.values())[:i])]
    scored = demo_scores(block_field(distinct), len(distinct), demos)
    scores = {name: float("inf") if f is None else scored[next(i for i, g in enumerate(distinct) if g is f)]
              for name, f in fits.items()}
    live = [name for name in fits if fits[name] is not None]
    return fits[min(live, key=lambda w: (not fits[w].certified_, scores[w]))], scores


__all__ = ["corrective_fits", "warp_choice"]

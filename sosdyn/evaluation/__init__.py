"""Evaluation of learned motions.

Modules: ``metrics`` (DTWD, SEA, velocity and goal errors), ``reproduction`` (reproductions
of the demonstrations, mean/std summaries), ``convergence`` (grid convergence, per start or
batched, with the call-budget policy), ``perturbations`` (the push / goal-change protocol),
``dsopt`` (the LASA protocol of ds-opt), ``baselines`` (GMR, DMP, CLF-DM). The integrators
themselves live in :mod:`sosdyn.lfd.rollout`.
"""

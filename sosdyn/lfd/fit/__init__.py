"""Fitting a CDSP model: functions on arrays, from demonstrations to a certified field.

Bottom up: ``gmm`` (the joint mixture and the position weights h_k), ``contraction`` (fields,
metric and the contraction matrix G_k of eq. (6) as numbers and as polynomial matrices),
``certificate`` (certify, extract, the independent check, collapse diagnostic), ``steps`` (one
convex step per module), ``refine`` (the mixture), ``learner`` (the alternating stages),
``warp`` (the diffeomorphic pre-warp of bumps), ``twist`` (a rotation about the goal by an angle
that depends on the distance to it), ``composite`` (the two as one map), ``corrective`` and ``rounds`` (fits made of several fits,
scored by training rollouts), ``params`` (the estimator's parameters and their checks), and on
top ``pipeline``: the whole fit path (demonstrations -> warp candidates -> core fits ->
certificate -> choice) that ``CDSP.fit`` calls once.
"""

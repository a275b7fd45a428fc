"""A safe bound where the solver's point has none: the posterior correction at a tightened re-solve.

The posterior shift (:mod:`.posterior`) needs every Gram block positive definite, by its
rounding margin, in the directions the constant monomial cannot reach. An interior-point
solver's point of a bound program lies on the boundary of the cone, where such a direction
can carry a tiny negative eigenvalue (Broyden tridiagonal, the Motzkin form times x^2 + y^2).
Solving again with every Gram block tightened to Q >= eps I (eps = MARGINS x the block's
largest entry, ``SOSProgram.tightened``) buys that margin for a slightly lower t; the shift
computed at the new point is a bound of the original program, because the posterior argument
uses only the numbers (the identity and the blocks' eigenvalues), not how they were found.
Where every exact certificate is singular along such a direction, the tightened programs are
infeasible and no point is found.
"""
from __future__ import annotations

import copy

import numpy as np

from ..errors import ResourceLimitError, UnverifiedSolutionError
from .gram import svec_to_matrix
from .posterior import safe_point
from .rigorous import ANSWERED

MARGINS = (1e-9, 1e-8, 1e-7)      # Q >= eps I relative to each block's largest entry, tried in order


def tightened_safe_point(solution, pattern):
    """:func:`~.posterior.safe_point` of ``solution`` (a lower-bound program, ``pattern`` =
    :func:`~.posterior.bound_pattern`) at the first tightened re-solve that admits one, read for
    the original program's decisions; None if none does (or the memory guard refuses the
    tightened program: its new blocks and face rows can be estimated far above the original's,
    Broyden tridiagonal n = 1000: 94.8 GiB against 0.5 GiB)."""
    program = solution.program
    scales = {id(b.psd): max(1.0, float(np.abs(svec_to_matrix(solution.values_of(b.ids), b.psd.size)).max()))
              for b in program.blocks if b.psd is not None and b.psd.cone == "psd" and b.psd.size}
    for rel in MARGINS:
        try:
            sol = program.tightened({}, {k: rel * v for k, v in scales.items()}).solve(retry=False)
        except ResourceLimitError:
            return None
        if sol.status not in ANSWERED or not np.isfinite(sol.x).all():
            continue
        view = copy.copy(solution)
        view.x = sol.values_of(solution.data.ids)
        try:
            return safe_point(view, pattern)
        except UnverifiedSolutionError:
            continue
    return None

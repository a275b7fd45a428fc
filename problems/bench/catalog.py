"""The list of SOS benchmark problems: textbook and dense ones (:mod:`.sos_problems`), then the
CDSP metric step (:mod:`.cdsp_problems`)."""
from __future__ import annotations

from . import sos_problems as S
from .cdsp_problems import cdsp_metric_resolve, cdsp_metric_step, cdsp_metric_theirs


def problems(quick: bool = False, dense_ns=(2, 3, 4, 5, 6)) -> list:
    """Every benchmark problem, textbook ones first, then dense ones, then the CDSP metric step."""
    P = S.Problem
    out = [
        P("Motzkin M", "known", S.feas(S.motzkin, "x y"), S.sos_theirs(S.motzkin, "x y"), expect="infeasible"),
        P("Motzkin (x²+y²)·M", "known", S.feas(lambda x, y: (x**2 + y**2) * S.motzkin(x, y), "x y"),
          S.sos_theirs(lambda x, y: (x**2 + y**2) * S.motzkin(x, y), "x y"), S.scale_resolve),
        P("Motzkin (x²+y²+1)·M", "known", S.feas(lambda x, y: (x**2 + y**2 + 1) * S.motzkin(x, y), "x y"),
          S.sos_theirs(lambda x, y: (x**2 + y**2 + 1) * S.motzkin(x, y), "x y"), S.scale_resolve),
        P("Motzkin x²·M", "known", S.feas(lambda x, y: x**2 * S.motzkin(x, y), "x y"),
          S.sos_theirs(lambda x, y: x**2 * S.motzkin(x, y), "x y"), expect="infeasible"),
        P("Motzkin max γ (unbounded/ill-posed)", "known", S.motzkin_max_gamma, S.motzkin_max_gamma_theirs,
          expect="any"),
        P("quartic form", "known", S.feas(S.quartic, "x y"), S.sos_theirs(S.quartic, "x y"), S.scale_resolve),
        P("Newton example", "known", S.feas(S.newton_example, "x y"), S.sos_theirs(S.newton_example, "x y"),
          S.scale_resolve),
        P("Horn form", "known", S.feas(S.horn_form(0), "x1 x2 x3 x4 x5"),
          S.sos_theirs(S.horn_form(0), "x1 x2 x3 x4 x5"), expect="infeasible"),
        P("Horn form · Σx²", "known", S.feas(S.horn_form(1), "x1 x2 x3 x4 x5"),
          S.sos_theirs(S.horn_form(1), "x1 x2 x3 x4 x5"), expect="any"),
        P("Chebyshev (max lead coef = 128)", "known", S.chebyshev, S.chebyshev_theirs),
        P("probability bound (1/37)", "known", S.probability, S.probability_theirs),
        P("SOS matrix", "known", S.sos_matrix, S.sos_matrix_theirs),
        P("Choi matrix (not SOS)", "known", S.choi, S.choi_theirs, expect="infeasible"),
        P("sosdemo2 Lyapunov", "known", S.sosdemo2, S.sosdemo2_theirs),
        P("Moore–Greitzer β=0.77", "known", S.moore_greitzer(0.77), S.moore_greitzer_theirs(0.77)),
    ]
    for n in dense_ns:
        out.append(P(f"dense degree-6 SOS n={n}", "dense", S.dense(n), S.dense_theirs(n), S.dense_resolve(n),
                     params={"n": n}))
    out.append(P("CDSP metric step (n=2, K=6, metric deg 2)", "cdsp", cdsp_metric_step(), cdsp_metric_theirs(),
                 cdsp_metric_resolve, params={"n": 2, "K": 6, "metric_degree": 2}))
    return out

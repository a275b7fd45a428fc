"""The learner's variants side by side on the four paper shapes (issue: CDSP learner).

For BendedLine, DoubleBendedLine, Leaf_1, Leaf_2 (K = 6, 7, 6, 6): velocity RMSE, DTWD (per
demo, mean), fit time, certified, and the collapse diagnostic, for linear + constant metric
(plain alternation), the paper's linear + degree-2 metric, ICA, cubic + degree-2 metric, each
with and without GMM refinement; GMR (no guarantee) as the accuracy ceiling.
Writes reports/learner_table.json and .md.  `python -m problems learner_table`
"""
from __future__ import annotations

import json
import time

import numpy as np

import sosdyn as sd
from sosdyn.evaluation.baselines import GMR
from sosdyn.evaluation.metrics import dtwd, velocity_rmse
from sosdyn.lfd.fit.params import PLAIN

from .settings import PAPER_SHAPES, REPORTS

SHAPES = {s.name: s.K for s in PAPER_SHAPES}
VARIANTS = {
    "linear, constant M, alternating": dict(metric_degree=0, solver_method="alternating"),
    "linear, degree-2 M (paper), alternating": dict(metric_degree=2, solver_method="alternating"),
    "linear, constant M, ICA": dict(metric_degree=0, solver_method="ica"),
    "cubic, degree-2 M, ICA start": dict(field_degree=3, metric_degree=2, solver_method="ica"),
}


def _dtwd_mean(model, demos):
    out = []
    for d in demos:
        traj = model.rollout(d.pos[0], duration=float(d.t[-1] - d.t[0]), dt=float(np.mean(np.diff(d.t))))
        out.append(dtwd(traj.pos, d.pos).total)
    return float(np.mean(out)), float(np.std(out))


def run_one(shape, name, kwargs, refine):
    demos = sd.load_lasa(shape)
    K = SHAPES[shape]
    t0 = time.perf_counter()
    if name == "GMR":
        model = GMR(n_components=K).fit(demos)
        certified, collapse = None, None
    else:
        model = sd.CDSP(**dict(PLAIN, n_components=K, refine_gmm=refine, **kwargs)).fit(demos)   # one plain fit each
        certified = bool(model.certified_)
        collapse = model.metric_collapse_ and model.metric_collapse_["constant_metric_certifies"]
    fit_s = time.perf_counter() - t0
    mean, std = _dtwd_mean(model, demos)
    return {"shape": shape, "variant": name, "refine_gmm": refine, "vel_rmse": velocity_rmse(model, demos),
            "dtwd_mean": mean, "dtwd_std": std, "fit_s": fit_s, "certified": certified,
            "metric_collapse": collapse}


def main(argv=None):
    rows = []
    for shape in SHAPES:
        rows.append(run_one(shape, "GMR", {}, False))
        for name, kw in VARIANTS.items():
            for refine in (False, True):
                rows.append(run_one(shape, name, kw, refine))
                r = rows[-1]
                print(f"{shape:17s} {name:42s} refine={refine!s:5s} rmse {r['vel_rmse']:7.2f} "
                      f"DTWD {r['dtwd_mean']:9.0f} fit {r['fit_s']:5.1f}s cert {r['certified']} "
                      f"collapse {r['metric_collapse']}", flush=True)
    out = REPORTS
    out.mkdir(exist_ok=True)
    (out / "learner_table.json").write_text(json.dumps(rows, indent=1))
    lines = ["| shape | variant | GMM refined | vel RMSE (mm/s) | DTWD total (mean ± std, 1000 pts) | "
             "fit (s) | certified | M(0) certifies (collapse) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['shape']} | {r['variant']} | {'yes' if r['refine_gmm'] else 'no'} | "
                     f"{r['vel_rmse']:.2f} | {r['dtwd_mean']:.0f} ± {r['dtwd_std']:.0f} | {r['fit_s']:.1f} | "
                     f"{'—' if r['certified'] is None else ('yes' if r['certified'] else 'NO')} | "
                     f"{'—' if r['metric_collapse'] is None else r['metric_collapse']} |")
    (out / "learner_table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0

"""Learning from noisy 3-D "kinesthetic" demonstrations (paper Fig. 7 analogue).

Four hand-made demonstrations in ``problems/data/demo3d/*.csv`` (made once by
``problems/data/make_demo3d.py``, fixed seed) are loaded with ``sosdyn.load_demos``
(velocities estimated from the noisy positions), CDSP-ICA and CDSP-cubic are fitted and
the reproductions drawn with ``trajectories_3d``. Writes ``figures/demo3d.{svg,png}``,
its caption and ``demo3d.json``; the main report picks the figure up.
"""
from __future__ import annotations

import time
from pathlib import Path

from threadpoolctl import threadpool_limits

import sosdyn as sd
from sosdyn.evaluation.convergence import grid_convergence_batched
from sosdyn.evaluation.reproduction import describe, evaluate_reproductions
from sosdyn.lfd.rollout import BudgetRollout
from sosdyn.report.figures import save_figure, trajectories_3d

from . import settings
from .jsonio import write_json
from .plumbing import parse_args
from .results import relpath
from .settings import REPORTS, Shape

DATA = Path(__file__).parent / "data" / "demo3d"
METHODS = ("CDSP-ICA", "CDSP-cubic")
K = 4


def load(n_demos=None, subsample=1):
    demos = sd.load_demos(sorted(DATA.glob("demo_*.csv")), units="mm", name="demo3d")
    if n_demos:
        demos = demos[:n_demos]
    return demos.subsample(subsample) if subsample > 1 else demos


def run(out_dir=REPORTS, *, quick=False, methods=METHODS, n_demos=None, subsample=1) -> dict:
    out_dir = Path(out_dir)
    demos = load(n_demos, subsample)
    shp = Shape("demo3d", K=2 if quick else K)
    results, repros = {}, {}
    with threadpool_limits(1):
        for name in methods:
            t0 = time.perf_counter()
            try:
                model = settings.METHODS[name].factory(shp, quick).fit(demos)
            except Exception as exc:
                results[name] = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
                print(f"demo3d {name}: FAILED {exc}")
                continue
            fit_s = time.perf_counter() - t0
            roll = BudgetRollout(model)
            rep = evaluate_reproductions(roll, demos)
            grid = grid_convergence_batched(model, demos, n_grid=3 if quick else 6)
            results[name] = {"status": "ok", "dtwd_total": describe(rep["dtwd"]),
                             "sea": describe(rep["sea"]), "goal_error": describe(rep["goal_error"]),
                             "grid_convergence": grid.fraction, "grid_starts": grid.n_starts,
                             "certified": bool(model.certified_), "fit_time_s": fit_s,
                             "metric_collapse": model.metric_collapse_}
            repros[name] = [t.pos for t in rep["trajectories"]]
            print(f"demo3d {name}: fit {fit_s:.1f} s, DTWD {rep['mean']['dtwd']:.1f} mm, "
                  f"certified {model.certified_}, grid {100 * grid.fraction:.0f} %", flush=True)
    write_json(out_dir / "demo3d.json", results)
    shown = next((m for m in reversed(methods) if m in repros), None)
    if shown is None:
        return {}
    fig = trajectories_3d([d.pos for d in demos], repros[shown], demos.goal,
                          title=f"3-D demonstrations: {shown}")
    paths = save_figure(fig, out_dir / "figures" / "demo3d")
    scores = "; ".join(f"{m}: DTWD {r['dtwd_total']['mean']:.0f} ± {r['dtwd_total']['std']:.0f} mm, "
                       f"certified {'yes' if r['certified'] else 'no'}, {r['grid_starts']} random starts "
                       f"{100 * r['grid_convergence']:.0f} % converged"
                       for m, r in results.items() if r["status"] == "ok")
    caption = (f"Learning from {len(demos)} noisy 3-D hand-guided demonstrations "
               f"(problems/data/demo3d, sensor noise 1 mm, tremor 3 mm), K = {shp.K}: demonstrations "
               f"(solid red) and {shown} reproductions (dashed blue). {scores}.")
    (out_dir / "figures" / "demo3d.caption.txt").write_text(caption)
    return {"demo3d": {"svg": relpath(paths["svg"], out_dir), "png": relpath(paths["png"], out_dir),
                       "caption": caption}}


def main(argv=None):
    args = parse_args(argv, "Fit CDSP-ICA and CDSP-cubic to the 3-D demonstrations")
    t0 = time.perf_counter()
    spec = run(args.out, quick=args.quick)
    for name, s in spec.items():
        print(f"{name}: {Path(args.out) / s['png']} ({time.perf_counter() - t0:.1f} s)")
    return 0

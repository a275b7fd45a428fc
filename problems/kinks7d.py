"""Kinks of 7-D reproductions (issue 22, item 10): peak acceleration with the plain and the tempered gating.

The synthetic 7-D task of :mod:`problems.demo7d` (5 noisy demonstrations, 100 Hz), fitted by
``CDSP(random_state=0, warp="none", gating="tempered")`` (K = 8) and by ``CDSP(random_state=0,
gating="tempered")`` (the default's warp choice). Each model is evaluated twice: with its tempered
weights (:mod:`sosdyn.lfd.fit.gmm`) and with the plain posterior (``bound`` None: the default
``gating="posterior"``, the default before issue 34, whose fit is the same, bit for bit; the default
``"smooth"`` is measured by tests/test_cli_joints.py and docs/findings.md). Rollouts are sampled every 2 ms; |xddot| by second differences:

* from the demonstrations' own starts (5), 6 s each, with the RMSE against the demonstrations
  (rollouts sampled at the demonstrations' 100 Hz, as ``demo7d`` scores them);
* from 12 random states uniform in the data's bounding box doubled about its centre (seed 0), 6 s.

Writes ``reports/kinks7d/kinks7d.json`` and ``kinks7d.{svg,png}`` (|xddot| against time from the
random start of the largest plain-gating peak, plain and tempered, per model).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.lfd.fit.gmm import with_bound
from sosdyn.report.figures.style import new_figure, save_figure

from .demo7d import demonstrations
from .jsonio import write_json
from .plumbing import parse_args
from .settings import REPORTS

DT, RANDOM_STARTS, DURATION = 0.002, 12, 6.0


def accelerations(model, x0, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """(t, |xddot|) of the rollout from x0 sampled every DT (second differences)."""
    run = model.rollout(x0, duration=duration, dt=DT)
    return run.t[1:-1], np.linalg.norm(np.diff(run.pos, 2, axis=0), axis=1) / DT ** 2


def measure(model, demos, starts) -> dict:
    """Peaks from the demonstrations' starts and from ``starts``, the profiles from ``starts``, the RMSE."""
    demo_peaks = [float(accelerations(model, d.pos[0], d.t[-1])[1].max()) for d in demos]
    profiles = [accelerations(model, x0, DURATION) for x0 in starts]
    rmse = []
    for d in demos:
        run = model.rollout(d.pos[0], duration=d.t[-1], dt=d.t[1] - d.t[0])
        m = min(len(run.t), len(d.t))
        rmse.append(float(np.sqrt(np.mean((run.pos[:m] - d.pos[:m]) ** 2))))
    random_peaks = [float(a.max()) for _, a in profiles]
    return {"demo_start_peak": max(demo_peaks), "random_start_peaks": random_peaks,
            "random_start_median": float(np.median(random_peaks)), "random_start_max": max(random_peaks),
            "mean_rmse_rad": float(np.mean(rmse)), "profiles": profiles}


def run(out_dir: Path, quick: bool = False) -> dict:
    demos = demonstrations(n_demos=3 if quick else 5, rate=25.0 if quick else 100.0)
    X = np.vstack([d.pos for d in demos])
    lo, hi = X.min(axis=0), X.max(axis=0)
    starts = (lo + hi) / 2 + np.random.default_rng(0).uniform(-1, 1, (3 if quick else RANDOM_STARTS, X.shape[1])) * (hi - lo)
    demo_peak = float(max(np.linalg.norm(np.diff(d.pos, 2, axis=0), axis=1).max() / (d.t[1] - d.t[0]) ** 2 for d in demos))
    results, figs = {"demonstrations_peak": demo_peak, "models": {}}, []
    for name, warp in (("warp='none'", "none"), ("warp='auto'", "auto")):
        model = sd.CDSP(random_state=0, warp=warp, gating="tempered", **(dict(n_components=2, max_iter=2) if quick else {})).fit(demos)
        tempered = measure(model, demos, starts)
        bound, model.mixture_ = model.mixture_.bound, with_bound(model.mixture_, None)
        plain = measure(model, demos, starts)
        bumps = 0 if model.warp_ is None else len(model.warp_["sigmas"])
        figs.append((f"{name} ({bumps} warp bumps)", plain.pop("profiles"), tempered.pop("profiles")))
        results["models"][name] = {"K": model.n_components_, "bound": bound, "plain": plain, "tempered": tempered}
        print(f"{name}: bound {bound:.1f}; peak |xddot| from the demos' starts {plain['demo_start_peak']:.2f} -> "
              f"{tempered['demo_start_peak']:.2f}; from random starts median {plain['random_start_median']:.1f} -> "
              f"{tempered['random_start_median']:.1f}, max {plain['random_start_max']:.1f} -> {tempered['random_start_max']:.1f} "
              f"rad/s^2; mean RMSE {plain['mean_rmse_rad']:.6f} -> {tempered['mean_rmse_rad']:.6f} rad", flush=True)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json(out_dir / "kinks7d.json", results)
    fig = new_figure(6 * len(figs), 3.6)
    for ax, (name, plain, tempered) in zip(fig.subplots(1, len(figs), squeeze=False)[0], figs):
        i = int(np.argmax([a.max() for _, a in plain]))
        for (t, a), label in ((plain[i], "plain posterior"), (tempered[i], "tempered off the data")):
            ax.semilogy(t, np.maximum(a, 1e-3), lw=1, label=f"{label}: peak {a.max():.0f}")
        ax.axhline(demo_peak, color="k", ls=":", lw=1, label=f"noisy demonstrations' samples: peak {demo_peak:.0f}")
        ax.set(title=f"7-D, {name}: random start #{i + 1}", xlabel="t (s)", ylabel="|acceleration| (rad/s²)")
        ax.legend(fontsize=8)
    results["figure"] = str(save_figure(fig, out_dir / "kinks7d")["png"])
    return results


def main(argv=None):
    args = parse_args(argv, "Peak accelerations of 7-D reproductions, plain and tempered gating")
    out = Path(args.out) / "kinks7d" if Path(args.out) == REPORTS else Path(args.out)
    print(f"kinks7d: {run(out, quick=args.quick)['figure']}")
    return 0

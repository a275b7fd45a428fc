"""A synthetic 7-D joint-space task: learn a certified CDSP from 5 noisy demonstrations.

Ground truth (never shown to the learner): a contracting latent system and a smooth map,

    ydot = A y - 0.1 y^3 (element-wise),   A = -D + S,  D = diag(0.6 .. 1.4), S skew,
    q = q* + s (y + 0.3 tanh(B y)),        |B|_2 = 1, so the map is a diffeomorphism (its
                                            Jacobian I + 0.3 diag(1 - tanh^2) B is invertible),

so the joint-space flow is contracting too (in the metric pulled back through the map) and
every trajectory ends at the goal q*. Five demonstrations start on a sphere of radius 2 in y,
are sampled at 100 Hz for 6 s, get 0.002 rad of Gaussian noise on the joint angles, and their
velocities are estimated from the noisy positions (``Demonstration.from_positions``), as for
recorded robot data. The model, ``CDSP.preset("paper", n_components=K)``, is fitted, certified
(SOS certificate + sampled check) and rolled out from every demonstration's start.

Writes ``reports/demo7d/demo7d.json`` (errors, certificate, timings) and the figure
``reports/demo7d/demo7d.{svg,png}`` (joint angles against time: demonstrations and
reproductions, one panel per joint).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import sosdyn as sd
from sosdyn.lfd import Demonstration, Demonstrations
from sosdyn.report.figures import save_figure, time_series

from .jsonio import write_json
from .plumbing import parse_args
from .settings import REPORTS

N, N_DEMOS, DURATION, RATE, NOISE, SCALE, K = 7, 5, 6.0, 100.0, 0.002, 0.25, 4
GOAL = np.array([0.0, -0.6, 0.0, -1.8, 0.0, 1.2, 0.8])        # a typical 7-DOF arm rest pose (rad)


def truth(seed: int = 0):
    """(latent field, map y -> q) of the ground-truth task (module docstring)."""
    rng = np.random.default_rng(seed)
    R = rng.normal(size=(N, N))
    A = -np.diag(np.linspace(0.6, 1.4, N)) + 1.5 * (R - R.T) / np.linalg.norm(R - R.T, 2)
    B = rng.normal(size=(N, N))
    B /= np.linalg.norm(B, 2)

    def field(y):
        return A @ y - 0.1 * y**3

    def to_joints(Y):
        return GOAL + SCALE * (Y + 0.3 * np.tanh(Y @ B.T))
    return field, to_joints


def demonstrations(seed: int = 0, n_demos: int = N_DEMOS, rate: float = RATE) -> Demonstrations:
    """``n_demos`` noisy joint-space demonstrations of the ground-truth task."""
    field, to_joints = truth(seed)
    rng = np.random.default_rng(seed + 1)
    t = np.arange(0.0, DURATION + 0.5 / rate, 1.0 / rate)
    out = []
    for i in range(n_demos):
        y0 = rng.normal(size=N)
        y0 *= 2.0 / np.linalg.norm(y0)
        Y = solve_ivp(lambda _t, y: field(y), (0.0, t[-1]), y0, t_eval=t, rtol=1e-8, atol=1e-10).y.T
        Q = to_joints(Y) + NOISE * rng.standard_normal(Y.shape)
        out.append(Demonstration.from_positions(t, Q, f"demo7d #{i + 1}"))
    return Demonstrations(out, "demo7d", "rad")


def run(out_dir: Path, quick: bool = False) -> dict:
    demos = demonstrations(n_demos=3 if quick else N_DEMOS, rate=25.0 if quick else RATE)
    t0 = time.perf_counter()
    model = sd.CDSP.preset("paper", n_components=2 if quick else K, random_state=0,
                           **(dict(max_iter=2, verify_samples=500) if quick else {})).fit(demos)
    fit_s = time.perf_counter() - t0
    runs, errors = [], []
    for d in demos:
        traj = model.rollout(d.pos[0], duration=d.t[-1], dt=d.t[1] - d.t[0])
        m = min(len(traj.t), len(d.t))
        errors.append({"demo": d.source, "rmse_rad": float(np.sqrt(np.mean((traj.pos[:m] - d.pos[:m]) ** 2))),
                       "final_goal_error_rad": float(np.linalg.norm(traj.pos[-1] - model.goal_))})
        runs.append((traj.t, traj.pos))
    results = {"dimension": N, "demos": len(demos), "samples_per_demo": len(demos[0].t), "noise_rad": NOISE,
               "K": model.n_components_, "params": {k: v for k, v in model.get_params().items() if k != "progress"},
               "certified": bool(model.certified_), "verification": str(model.verification_),
               "fit_s": fit_s, "timings": model.timings_, "sdp_solves": sum("status" in r for r in model.history_),
               "reproduction": errors,
               "mean_rmse_rad": float(np.mean([e["rmse_rad"] for e in errors])),
               "max_final_goal_error_rad": float(max(e["final_goal_error_rad"] for e in errors))}
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json(out_dir / "demo7d.json", results)
    fig = time_series(runs, model.goal_, units="rad", demos=[(d.t, d.pos) for d in demos],
                      title=f"7-D joint space: {len(demos)} noisy demonstrations and their\nCDSP reproductions "
                            f"(K = {model.n_components_}, certified: {'yes' if model.certified_ else 'NO'})")
    paths = save_figure(fig, out_dir / "demo7d")
    results["figure"] = {k: str(v) for k, v in paths.items()}
    return results


def main(argv=None):
    args = parse_args(argv, "Learn a certified CDSP from 5 noisy 7-D joint-space demonstrations")
    out = Path(args.out) / "demo7d" if Path(args.out) == REPORTS else Path(args.out)
    res = run(out, quick=args.quick)
    print(f"demo7d: fit {res['fit_s']:.1f} s, certified {res['certified']}, mean RMSE "
          f"{res['mean_rmse_rad']:.4f} rad, max final goal error {res['max_final_goal_error_rad']:.2e} rad; "
          f"{res['figure']['png']}")
    return 0

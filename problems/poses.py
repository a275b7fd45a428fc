"""``make poses``: certified pose models (position + orientation) on the robottasks Franka demos.

Per task (the shipped ``sd.load_dataset("robottasks/<task>")``, positions in cm, orientations): the held-out
protocol of :func:`sosdyn.evaluation.poses.evaluate_pose_set` (first 6 of 9 demos train, preprocessed;
3 test; reproductions from the 20th kept sample read at the demo's period; position DTWD and orientation
DTW against copying the nearest training demo; final errors; arrival; the certified excursion bound),
then the detour tests (:func:`~sosdyn.evaluation.poses.detour_tests`: orientation-only starts 90, 170 and
179 deg off at the goal position and a 30 deg turn of the goal orientation after arrival, about the three
axes and one oblique axis) and the far starts (:func:`~sosdyn.evaluation.poses.far_starts`: every test
start turned 90-179 deg from the goal orientation). Writes reports/poses/{results.json,index.html,*.png}.
``--quick``: one task.
"""
from __future__ import annotations

import argparse
import html
import json
import time
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.evaluation.dsopt import START_INDEX
from sosdyn.evaluation.poses import ANG_TOL, POS_TOL, detour_tests, evaluate_pose_set, far_starts
from sosdyn.lfd.data.pose import from_chart
from sosdyn.lfd.model.pose import PoseCDSP, PoseTrajectory
from sosdyn.report.figures.poses import detour_figure, drift_figure, orientation_error, pose_paths

TASKS = ("openbox", "bottle2shelf", "platestandingtolying", "pouring")
TARGET = 1.5                          # paths within 1.5x copying the nearest demo
AXES = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, -0.48, 0.64]])
DETOUR_S = 40.0                       # duration of the detour and far-start rollouts (s)
REPO = Path(__file__).resolve().parents[1]


def run_task(task: str, out_dir: Path) -> dict:
    demos = sd.load_dataset(f"robottasks/{task}")
    r = evaluate_pose_set(lambda train: PoseCDSP().fit(train), demos)
    model, diag = r.pop("model"), r["diag"]
    train, test = r.pop("train"), r.pop("test")
    trajs = [PoseTrajectory(t + d.t[START_INDEX] - d.t[0], S[:, :3], from_chart(S[:, 3:], model.goal_quat_), None)
             for (t, S), d in zip(r.pop("reproductions"), test)]
    t0 = time.perf_counter()
    detours = detour_tests(model, DETOUR_S, AXES, diag)
    far = far_starts(model, test, DETOUR_S, AXES, diag)
    r["detour_s"] = time.perf_counter() - t0
    labels = [f"test {Path(d.source).stem}" for d in test]
    figs = {"paths": pose_paths(task, train, test, trajs, model.goal_pos_, "cm", labels),
            "orientation": orientation_error(task, test, trajs, model.goal_quat_, labels),
            "detours": detour_figure(task, detours["cases"], diag, "cm")}
    for kind, fig in figs.items():
        fig.savefig(out_dir / f"{task}_{kind}.png", dpi=130)
    cases = [{k: v for k, v in c.items() if k not in ("t", "angle", "distance", "displacement")} for c in detours["cases"]]
    r["targets"] = {"certified": bool(model.certified_), "pos_le_1.5x_copy": r["pos_ratio"] <= TARGET,
                    "ori_le_1.5x_copy": r["ori_ratio"] <= TARGET, "final_pos_le_1pct": r["final_pos_frac"] <= POS_TOL,
                    "final_ang_le_1deg": r["final_ang_deg"] <= ANG_TOL,
                    "detour_lt_1pct": detours["max_displacement_frac"] < POS_TOL,
                    "far_starts_converge": far["final_pos_frac"] <= POS_TOL and far["final_ang_deg"] <= ANG_TOL}
    floor = model.orientation_.floor_
    block = {"gamma": float(model.orientation_.gamma), "settle_rate": None if floor is None else floor["rate"],
             "settle_deg": model.goal_tol_deg}
    return dict(r, task=task, detours={"max_displacement_frac": detours["max_displacement_frac"], "cases": cases},
                orientation_block=block,
                far_starts=far, still=model.still_, end_alignment_deg=list(model.orientation_moved_deg_),
                warp=model.position_.warp_scores_, figures={k: f"{task}_{k}.png" for k in figs})


def fmt(v, digits=2) -> str:
    return "—" if v is None else (("yes" if v else "NO") if isinstance(v, bool) else f"{v:.{digits}f}")


def _table(head, rows) -> str:
    return "<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>" + "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows) + "</table>"


def write_html(results: dict, out_dir: Path) -> Path:
    """reports/poses/index.html: the accuracy table, the detour and far-start tests, the figures."""
    accuracy = _table(
        ("task", "certified", "pos DTWD / copy", "ori DTW / copy", "pos / copy at nearest start",
         "ori / copy at nearest start", "ori floor / copy", "final pos (% diag)",
         "final ori (deg)",
         "arrival / duration (max)", "excursion bound (× diag)", "fit (s)"),
        [(r["task"], fmt(r["certified"]), f"{r['pos_ratio']:.2f} ({r['pos_dtwd']:.0f} / {r['copy_pos']:.0f})",
          f"{r['ori_ratio']:.2f} ({r['ori_dtw']:.0f} / {r['copy_ori']:.0f})", fmt(r["pos_start_ratio"]),
          fmt(r["ori_start_ratio"]), fmt(r["ori_floor_ratio"]),
          fmt(100 * r["final_pos_frac"], 3),
          fmt(r["final_ang_deg"], 3), fmt(r["arrival_ratio"]), fmt(r["excursion_bound"]), fmt(r["fit_s"], 1))
         for r in results["tasks"]])
    detours = _table(
        ("task", "orientation-only starts / goal turns", "largest position move (% diag)",
         "final angle, worst (deg)", "far starts (90–179°)", "far: final pos (% diag), angle (deg)",
         "far: largest rise of the angle (deg)"),
        [(r["task"], f"{sum(c['kind'] != 'goal turn' for c in r['detours']['cases'])} / "
                     f"{sum(c['kind'] == 'goal turn' for c in r['detours']['cases'])}",
          f"{100 * r['detours']['max_displacement_frac']:.3g}",
          f"{max(c['final_angle_deg'] for c in r['detours']['cases']):.2g}", r["far_starts"]["n"],
          f"{100 * r['far_starts']['final_pos_frac']:.2g}, {r['far_starts']['final_ang_deg']:.2g}",
          f"{r['far_starts']['max_angle_rise_deg']:.2g}") for r in results["tasks"]])
    settle = "; ".join(html.escape(r["task"]) + f": rate {r['orientation_block']['gamma']:.3f}/s, " + (
        "no floor needed" if r["orientation_block"]["settle_rate"] is None else
        f"floor {r['orientation_block']['settle_rate']:.2f}/s within {r['orientation_block']['settle_deg']:g}°")
        for r in results["tasks"])
    targets = "".join(f"<li><b>{html.escape(r['task'])}</b>: " + ", ".join(
        f"{k} {'✓' if v else '✗'}" for k, v in r["targets"].items()) + "</li>" for r in results["tasks"])
    captions = {
        "paths": "training demos (grey), test demos (black, dashed) and the model's reproductions from their 20th "
                 "kept sample (colour), with orientation frames (x red, y green, z blue) along each reproduction.",
        "orientation": "angle to the goal orientation over time: test demos (dashed) and reproductions (solid); the "
                       "dotted line is 1°. The test demos' own ends scatter around the goal (only the training "
                       "ends were aligned to it).",
        "detours": "the detour tests: at the goal position, starts turned 90°, 170° and 179° about four axes "
                   "(solid), and a 30° turn of the goal orientation after arrival (dashed, at t = 10 s): angle to "
                   "the (current) goal orientation, and how far the position moved."}
    figs = "".join(f"<figure><img src=\"{html.escape(r['figures'][k])}\" alt=\"{html.escape(r['task'])} {k}\">"
                   f"<figcaption>{html.escape(r['task'])}: {cap}</figcaption></figure>"
                   for r in results["tasks"] for k, cap in captions.items())
    rows = [row for r in results["tasks"] for row in r["tests"]]
    cases = len(rows)

    def latest(key):
        return sum(int(np.argmin(row[key])) == len(row[key]) - 1 for row in rows)
    preprocess = "".join(f"<li><b>{html.escape(r['task'])}</b>: " + "; ".join(html.escape(line) for line in r["preprocess"])
                         + "</li>" for r in results["tasks"])
    page = f"""<!doctype html><html lang="en"><head><meta charset="utf-8"><title>sosdyn: poses</title>
<style>
  :root {{ --accent: #0072B2; --muted: #5f6670; --line: #d9dde3; }}
  html {{ font-family: "DejaVu Sans", "Liberation Sans", Arial, sans-serif; font-size: 14px; color: #1d232b;
         line-height: 1.45; }}
  body {{ max-width: 1120px; margin: 0 auto; padding: 24px 28px 60px; }}
  h1 {{ font-size: 1.9rem; margin: 0 0 4px; }}
  h2 {{ font-size: 1.3rem; margin: 2.2rem 0 0.6rem; padding-bottom: 4px; border-bottom: 2px solid var(--accent); }}
  .subtitle {{ color: var(--muted); }}
  table {{ border-collapse: collapse; font-size: 0.92em; font-variant-numeric: tabular-nums; }}
  td, th {{ border-bottom: 1px solid var(--line); padding: 4px 8px; text-align: right; }}
  td:first-child, th:first-child {{ text-align: left; }}
  figure {{ margin: 1rem 0 1.6rem; text-align: center; }} figure img {{ max-width: 100%; height: auto; }}
  figcaption {{ color: var(--muted); font-size: 0.92em; }}
</style></head><body>
<h1>Poses: position and orientation, certified, without detours</h1>
<p class="subtitle">robottasks (Franka Panda, CLFD; positions in cm, inferred), default <code>PoseCDSP()</code>: the
position CDSP and an orientation CDSP in the identity metric (docs/theory.md, "Poses"); built by
<code>make poses</code>{' --quick' if results['quick'] else ''} in {results['total_s']:.0f} s.</p>
<h2>Accuracy on held-out demos</h2>{accuracy}
<p>Protocol (<code>sosdyn.evaluation.poses</code>): the first 6 of 9 demos train (preprocessed: both parts resampled,
rest-trimmed, smoothed, ends aligned), the other 3 test (rest trimmed only); every 2nd sample; reproductions by explicit
Euler (0.01 s) from each test demo's 20th kept sample until both parts rest, <b>read at the demo's own period</b>
(1/30 s) before the cumulative DTW. DTWD (positions, cm) and orientation DTW (geodesic angle, deg) are sums along the
alignment, means over the test demos; "copy" replays the training demo nearest to the test demo as recorded (the
issue's target, ≤ 1.5× copy: a pick made with the test demo in hand, as no robot could); "copy at nearest start"
replays the training demo whose first sample is nearest the reproduction's start (|Δp| / diag + angle / 180°), what a
robot given only the start could do. Final errors: worst test
reproduction, to the model's goal pose. Arrival: within 1 % of the diagonal and 1° of the goal pose, over the demo's
remaining duration. Orientation floor: the test demo itself with its end turned onto the model's goal orientation
(a reproduction that is exact but ends at the goal, as a certified model must), over copy: the part of the ratio the
test demos' end scatter alone costs. Excursion bound: the largest excursion outside the training box (× its diagonal) that the position
block's certificate allows from the test starts.</p>
<figure><img src="drift.png" alt="the training demos by recording order against the test demos">
<figcaption>Each training demo, replayed as recorded, against the three test demos (the last recorded), in recording
order: its mean DTW over the test demos / copy's (1 = it is the nearest for every test demo); the star is the model,
the dotted line the 1.5× target. The baseline's pick (made with the test demo in hand) is the latest training demo
in {latest("train_ori")} of the {cases} orientation cases and {latest("train_pos")} of the {cases} position cases: the demonstrator
drifted while recording, and a model fitted to all training demos alike follows their average (docs/theory.md,
"What still misses the 1.5× target").</figcaption></figure>
<h2>Detours and far starts</h2>{detours}
<p>The position never depends on the orientation (the cascade), so an orientation-only start or a turn of the goal
orientation moves it by exactly 0; the orientation block's identity metric makes the angle to the goal orientation
non-increasing, so every start converges, up to a half turn, with no refusal. Its certified rate is 0.5 / T (T the
training demos' median duration) and within the settle zone (goal_tol_deg of the goal) a speed floor ends the
exponential tail, a time change that keeps the paths and the certificate: {settle}.</p>
<h2>Targets</h2><ul>{targets}</ul>
<h2>Preprocessing (training demos)</h2><ul>{preprocess}</ul>
<h2>Figures</h2>{figs}
</body></html>
"""
    path = out_dir / "index.html"
    path.write_text(page)
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m problems poses", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "reports" / "poses")
    parser.add_argument("--quick", action="store_true", help="one task")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    results = {"quick": args.quick, "tasks": []}
    for task in TASKS[:1] if args.quick else TASKS:
        r = run_task(task, args.out)
        results["tasks"].append(r)
        print(f"{task}: pos {r['pos_ratio']:.2f}x ori {r['ori_ratio']:.2f}x copy, final {100 * r['final_pos_frac']:.2g} % "
              f"{r['final_ang_deg']:.2g} deg, detour {100 * r['detours']['max_displacement_frac']:.2g} %, "
              f"far starts {r['far_starts']}, fit {r['fit_s']:.0f} s", flush=True)
    drift_figure([{**{k: [row[k] for row in r["tests"]] for k in ("train_pos", "train_ori")}, **{
        k: r[k] for k in ("task", "copy_pos", "copy_ori", "pos_ratio", "ori_ratio")}} for r in results["tasks"]],
        TARGET).savefig(args.out / "drift.png", dpi=130)
    results["total_s"] = time.perf_counter() - t0
    (args.out / "results.json").write_text(json.dumps(results, indent=1, default=float) + "\n")
    print(write_html(results, args.out))
    return 0

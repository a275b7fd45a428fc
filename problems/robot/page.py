"""The robot page (``reports/robot/index.html``): key frames and clip from the simulator, the
end-effector paths against the demonstrations (3-D), the success table and every trial.

Styled with the user report's stylesheet (the ``<style>`` block of
``sosdyn/report/templates/report.html.j2``, read, not copied).
"""
from __future__ import annotations

import html
import re
from importlib.resources import files
from pathlib import Path

import numpy as np
from matplotlib.lines import Line2D

from sosdyn.report.figures.style import DEMO_COLOR, GOAL_STYLE, method_color, new_figure, save_figure, styled

from .frames import save_gif, save_key_frames
from .tasks import N_TRAIN
from .arm import RATE
from .trials import GOAL_WINDOW, MAX_SPEED, PUSH_FORCE, PUSH_STEPS, PUSH_WINDOW, TOL

MARGIN = 0.1                 # m around the demonstrations in the 3-D figure

def report_css() -> str:
    template = files("sosdyn.report").joinpath("templates/report.html.j2").read_text()
    return re.search(r"<style>(.*?)</style>", template, re.S).group(1)


@styled
def paths_figure(paths: dict, demos_of: dict, rows: list):
    """One 3-D panel per task: training demos (grey), held-out demos (red), each method's paths
    (its colour), the training goal (black star) and moved goals (hollow stars); equal axes on the
    demonstrations' box grown by :data:`MARGIN`, path points outside it not drawn."""
    tasks = list(demos_of)
    cols = min(2, len(tasks))
    fig = new_figure(5.2 * cols, 5.0 * ((len(tasks) + cols - 1) // cols))
    index = {(r["task"], r["method"]): [] for r in rows}
    for (task, method, _), path in paths.items():
        index[(task, method)].append(path)
    for j, task in enumerate(tasks):
        ax = fig.add_subplot((len(tasks) + cols - 1) // cols, cols, j + 1, projection="3d")
        demos = demos_of[task]
        X = np.vstack([d.pos for d in demos])
        lo, hi = X.min(axis=0) - MARGIN, X.max(axis=0) + MARGIN
        for k, d in enumerate(demos):
            ax.plot(*d.pos.T, color="0.6" if k < N_TRAIN else DEMO_COLOR, lw=1.0 if k < N_TRAIN else 1.4)
        for method, style in (("CDSP", "-"), ("GMR", "--")):
            for path in index.get((task, method), []):
                inside = np.where(((path["x"] >= lo) & (path["x"] <= hi)).all(axis=1, keepdims=True), path["x"], np.nan)
                ax.plot(*inside.T, style, color=method_color(method), lw=1.1)
                moved = path["goal"][-1]
                if not np.allclose(moved, demos.goal):
                    ax.plot(*moved[:, None], marker="*", markersize=9, color="none",
                            markeredgecolor=method_color(method), linestyle="none")
        ax.plot(*demos.goal[:, None], **GOAL_STYLE)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), title=task)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.tick_params(labelsize=7)
    handles = [("training demos", "0.6", "-"), ("held-out demos", DEMO_COLOR, "-"),
               ("CDSP", method_color("CDSP"), "-"), ("GMR", method_color("GMR"), "--")]
    fig.legend([Line2D([], [], color=c, ls=s) for _, c, s in handles], [h[0] for h in handles],
               loc="outside lower center", ncols=4)
    return fig


def summary(rows: list) -> list[dict]:
    """Per task and method: trials, successes, median / worst final error (mm), median / worst
    time to goal (s), the undisturbed held-out starts' mean path deviation (mm), peak joint speed."""
    out = []
    for key in dict.fromkeys((r["task"], r["method"]) for r in rows):
        mine = [r for r in rows if (r["task"], r["method"]) == key]
        err = [1e3 * r["final_pos_err_m"] for r in mine]
        ttg = [r["time_to_goal_s"] for r in mine if r["time_to_goal_s"] is not None]
        dev = [1e3 * r["path_deviation_m"] for r in mine if r["path_deviation_m"] is not None
               and not r["push"] and not r["goal_moved"]]
        out.append({"task": key[0], "method": key[1], "trials": len(mine),
                    "success": sum(r["success"] for r in mine),
                    "limit_hits": sum(r["joint_limit_hit"] for r in mine),
                    "err_median_mm": float(np.median(err)), "err_max_mm": max(err),
                    "ttg_median_s": float(np.median(ttg)) if ttg else None,
                    "ttg_max_s": max(ttg) if len(ttg) == len(mine) else None,
                    "path_dev_mm": float(np.mean(dev)) if dev else None,
                    "peak_cmd_qdot": max(r["peak_commanded_joint_speed_rad_s"] for r in mine)})
    return out


def _num(v, fmt):
    return "—" if v is None else format(v, fmt)


def summary_table(rows: list) -> str:
    head = ("<tr><th class='key'>task</th><th class='key'>method</th><th>success</th><th>limit hits</th>"
            "<th>final error median / worst (mm)</th><th>time to goal median / worst (s)</th>"
            "<th>path deviation, undisturbed (mm)</th><th>peak commanded joint speed (rad/s)</th></tr>")
    body = []
    for s in summary(rows):
        ok = "pass" if s["success"] == s["trials"] else "fail"
        body.append(f"<tr><td class='key'>{s['task']}</td><td class='key'>{s['method']}</td>"
                    f"<td class='{ok}'>{s['success']}/{s['trials']}</td><td>{s['limit_hits']}</td>"
                    f"<td>{s['err_median_mm']:.2f} / {s['err_max_mm']:.1f}</td>"
                    f"<td>{_num(s['ttg_median_s'], '.1f')} / {_num(s['ttg_max_s'], '.1f')}</td>"
                    f"<td>{_num(s['path_dev_mm'], '.1f')}</td><td>{s['peak_cmd_qdot']:.2f}</td></tr>")
    return f"<div class='table-wrap'><table><thead>{head}</thead><tbody>{''.join(body)}</tbody></table></div>"


def trials_table(rows: list) -> str:
    cols = ("method", "task", "start", "demo", "push", "goal_moved", "success", "final_pos_err_m",
            "time_to_goal_s", "path_deviation_m", "push_displacement_m", "peak_joint_speed_rad_s",
            "joint_limit_hit")
    fmt = {"final_pos_err_m": ".5f", "time_to_goal_s": ".1f", "path_deviation_m": ".4f",
           "push_displacement_m": ".3f", "peak_joint_speed_rad_s": ".2f"}
    head = "".join(f"<th>{c.replace('_', ' ')}</th>" for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(_num(r[c], fmt.get(c, '')))}</td>" for c in cols)
                   + "</tr>" for r in rows)
    return f"<div class='table-wrap'><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>"


def write_page(out_dir, results: dict, paths: dict, demos_of: dict, showcase) -> Path:
    """Figures, frames, clip and ``index.html`` in ``out_dir``."""
    out_dir = Path(out_dir)
    fig_dir = out_dir / "figures"
    rows, meta = results["trials"], results["meta"]
    save_figure(paths_figure(paths, demos_of, rows), fig_dir / "paths", dpi=110)
    parts = []
    if showcase is not None:
        r, rec = showcase["row"], showcase["recorder"]
        err_mm = 1e3 * r["final_pos_err_m"]
        titles = {"push": f"push {PUSH_FORCE:.0f} N for {1e3 * PUSH_STEPS / RATE:.0f} ms",
                  "goal moved": f"goal moved {1e2 * np.linalg.norm(r['goal_shift_m']):.0f} cm",
                  "end": f"end: {err_mm:.2f} mm from the goal"}
        save_key_frames(rec.frames, titles, r["method"], fig_dir / "frames")
        where = f"held-out demo {r['demo']}" if r["demo"] is not None else "a random start"
        parts.append(f"<figure><img src='figures/frames.png' alt='simulator frames'><figcaption><b>The "
                     f"{r['task']} task, CDSP from {where}</b>, rendered by pybullet's TinyRenderer: red line "
                     f"the held-out demonstration, blue the gripper's path so far, red ball the goal. "
                     f"Pushed at t = {r['push_time_s']:.1f} s (displaced {1e2 * r['push_displacement_m']:.0f} cm), "
                     f"goal moved at t = {r['goal_move_time_s']:.1f} s; within {TOL * 1e3:.0f} mm of the new "
                     f"goal from t = {_num(r['time_to_goal_s'], '.1f')} s.</figcaption></figure>")
        if rec.clip:
            save_gif(rec.clip, fig_dir / "trial.gif", f"CDSP, {r['task']}")
            parts.append("<figure><img src='figures/trial.gif' alt='animated trial'><figcaption>The same "
                         "trial, one frame per 0.5 s played at 10 frames per second (5x real time)."
                         "</figcaption></figure>")
    methods = dict.fromkeys(x["method"] for x in rows)
    verdict = "; ".join(f"{m}: {sum(x['success'] for x in rows if x['method'] == m)} of "
                        f"{sum(x['method'] == m for x in rows)} trials succeeded" for m in methods)
    shift = ", ".join(f"{v:+.3f}" for v in meta["transform"]["shift_m"])
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>sosdyn robot trials</title><style>{report_css()}</style></head><body>
<h1>A learned motion on a simulated robot</h1>
<p class="subtitle">{html.escape(meta['simulator'])}; {html.escape(meta['robot'])}.
{'Quick run (one task). ' if meta['quick'] else ''}{verdict}.</p>
<h2>Setup</h2>
<p><b>Demonstrations</b>: the real Franka Panda RoboTasks recordings (Auddy et al. 2023; 9 kinesthetic
demonstrations per task, positions in cm), mapped into the simulated Panda's base frame by
<code>x_sim = x_cm / 100 + ({shift}) m</code>: one translation for all tasks, placing the centre of their
bounding box 0.5 m in front of the robot, 0.3 m above the floor; every 50th sample checked is reachable with the gripper
pointing down (inverse kinematics error &lt; 0.1 mm, joints at least
{min(v['min_joint_margin_deg'] for v in meta['reachability'].values()):.0f}° from their limits).
Models learn from demonstrations 0-{N_TRAIN - 1} (positions in m); demonstrations {N_TRAIN}-8 give held-out starts.</p>
<p><b>Controller</b> ({meta['rate_hz']:.0f} Hz, the simulator's rate): the model's velocity for the current goal,
scaled down to at most {MAX_SPEED} m/s; joint velocities by damped least squares on the 6-D Jacobian (position
from the model, orientation held pointing down), joint-limit avoidance in the null space, sent with
<code>VELOCITY_CONTROL</code> at the Panda's torque limits. <b>Disturbances</b>: a horizontal push of
{PUSH_FORCE:.0f} N for {1e3 * PUSH_STEPS / RATE:.0f} ms on the end effector at a random time
({PUSH_WINDOW[0]:.0%}-{PUSH_WINDOW[1]:.0%} of the demonstrations' duration); the goal moved by
{meta['goal_shift_m'] * 100:.0f} cm in a random direction at a random time
({GOAL_WINDOW[0]:.0%}-{GOAL_WINDOW[1]:.0%}). <b>Success</b>: within {TOL * 1e3:.0f} mm of the current
goal at the end of the trial (twice the demonstrations' duration), no joint within 0.5° of a limit.
Baseline: GMR (no stability guarantee) through the same controller.</p>
<h2>One trial in the simulator</h2>{''.join(parts)}
<h2>End-effector paths</h2>
<figure><img src="figures/paths.png" alt="3-D paths"><figcaption>Paths of every trial against the demonstrations
(grey: training, red: held-out); black star the demonstrations' goal, hollow stars moved goals. Axes: the
demonstrations' box grown by {MARGIN * 100:.0f} cm; paths leaving it (GMR's) are cut at its faces.</figcaption></figure>
<h2>Success</h2>{summary_table(rows)}
<h2>Every trial</h2><details><summary>{len(rows)} trials</summary>{trials_table(rows)}</details>
<p class="note">Numbers: <code>results.json</code> (meta and one row per trial). Made by <code>make robot</code>.</p>
</body></html>
"""
    path = out_dir / "index.html"
    path.write_text(page)
    return path

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
from .trials import (GOAL_TURN_DEG, GOAL_WINDOW, MAX_ANGULAR_SPEED, MAX_SPEED, PUSH_FORCE, PUSH_STEPS, PUSH_TORQUE,
                     PUSH_WINDOW, TOL)
from .trials import ORI_TOL_DEG as TOL_DEG

METHODS = ("CDSP", "GMR", "PoseCDSP", "GMR pose")

MARGIN = 0.1                 # m around the demonstrations in the 3-D figure

def report_css() -> str:
    template = files("sosdyn.report").joinpath("templates/report.html.j2").read_text()
    return re.search(r"<style>(.*?)</style>", template, re.S).group(1)


STYLES = {"CDSP": "-", "GMR": "--", "PoseCDSP": "-", "GMR pose": "--"}


@styled
def paths_figure(paths: dict, demos_of: dict, rows: list, methods=("CDSP", "GMR")):
    """One 3-D panel per task: training demos (grey), held-out demos (red), the paths of each of
    ``methods`` (its colour), the training goal (black star) and moved goals (hollow stars); equal axes on
    the demonstrations' box grown by :data:`MARGIN`, path points outside it not drawn."""
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
        for method in methods:
            for path in index.get((task, method), []):
                inside = np.where(((path["x"] >= lo) & (path["x"] <= hi)).all(axis=1, keepdims=True), path["x"], np.nan)
                ax.plot(*inside.T, STYLES[method], color=method_color(method, METHODS), lw=1.1)
                moved = path["goal"][-1, :3]
                if not np.allclose(moved, demos.goal):
                    ax.plot(*moved[:, None], marker="*", markersize=9, color="none",
                            markeredgecolor=method_color(method, METHODS), linestyle="none")
        ax.plot(*demos.goal[:, None], **GOAL_STYLE)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), title=task)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("z (m)")
        ax.tick_params(labelsize=7)
    handles = [("training demos", "0.6", "-"), ("held-out demos", DEMO_COLOR, "-")] + \
        [(m, method_color(m, METHODS), STYLES[m]) for m in methods]
    fig.legend([Line2D([], [], color=c, ls=s) for _, c, s in handles], [h[0] for h in handles],
               loc="outside lower center", ncols=4)
    return fig


@styled
def angles_figure(paths: dict, rows: list, methods=("PoseCDSP", "GMR pose")):
    """Angle to the current goal orientation over time, one panel per task, every pose trial of
    ``methods`` (its colour; pushes twist the gripper, goal moves turn the goal); the 2 deg success line."""
    tasks = list(dict.fromkeys(r["task"] for r in rows if r["method"] in methods))
    fig = new_figure(4.6 * len(tasks), 3.2)
    axes = np.atleast_1d(fig.subplots(1, len(tasks)))
    for ax, task in zip(axes, tasks):
        for (t_, method, _), path in paths.items():
            if t_ == task and method in methods:
                q, g = path["quat"], path["goal"][:, 3:]
                angle = np.degrees(2 * np.arccos(np.clip(np.abs(np.einsum("ti,ti->t", q, g)), 0, 1)))
                ax.plot(path["t"], angle, STYLES[method], color=method_color(method, METHODS), lw=1.0)
        ax.axhline(TOL_DEG, color="0.4", ls=":", lw=1)
        ax.set(title=task, xlabel="t (s)", ylim=(0, None))
    axes[0].set_ylabel("angle to goal orientation (deg)")
    fig.legend([Line2D([], [], color=method_color(m, METHODS), ls=STYLES[m]) for m in methods], list(methods),
               loc="outside lower center", ncols=len(methods))
    return fig


def summary(rows: list) -> list[dict]:
    """Per task and method: trials, successes, median / worst final error (mm), median / worst
    time to goal (s), the undisturbed held-out starts' mean path deviation (mm), peak joint speed."""
    out = []
    for key in dict.fromkeys((r["task"], r["method"]) for r in rows):
        mine = [r for r in rows if (r["task"], r["method"]) == key]
        err = [1e3 * r["final_pos_err_m"] for r in mine]
        ori = [r["final_ori_err_deg"] for r in mine]
        ttg = [r["time_to_goal_s"] for r in mine if r["time_to_goal_s"] is not None]
        dev = [1e3 * r["path_deviation_m"] for r in mine if r["path_deviation_m"] is not None
               and not r["push"] and not r["goal_moved"]]
        out.append({"task": key[0], "method": key[1], "trials": len(mine),
                    "success": sum(r["success"] for r in mine),
                    "limit_hits": sum(r["joint_limit_hit"] for r in mine),
                    "err_median_mm": float(np.median(err)), "err_max_mm": max(err), "ori_max_deg": max(ori),
                    "ttg_median_s": float(np.median(ttg)) if ttg else None,
                    "ttg_max_s": max(ttg) if len(ttg) == len(mine) else None,
                    "path_dev_mm": float(np.mean(dev)) if dev else None,
                    "peak_cmd_qdot": max(r["peak_commanded_joint_speed_rad_s"] for r in mine)})
    return out


def _num(v, fmt):
    return "—" if v is None else format(v, fmt)


def summary_table(rows: list) -> str:
    head = ("<tr><th class='key'>task</th><th class='key'>method</th><th>success</th><th>limit hits</th>"
            "<th>final error median / worst (mm)</th><th>final angle, worst (deg)</th>"
            "<th>time to goal median / worst (s)</th>"
            "<th>path deviation, undisturbed (mm)</th><th>peak commanded joint speed (rad/s)</th></tr>")
    body = []
    for s in summary(rows):
        ok = "pass" if s["success"] == s["trials"] else "fail"
        body.append(f"<tr><td class='key'>{s['task']}</td><td class='key'>{s['method']}</td>"
                    f"<td class='{ok}'>{s['success']}/{s['trials']}</td><td>{s['limit_hits']}</td>"
                    f"<td>{s['err_median_mm']:.2f} / {s['err_max_mm']:.1f}</td><td>{s['ori_max_deg']:.2f}</td>"
                    f"<td>{_num(s['ttg_median_s'], '.1f')} / {_num(s['ttg_max_s'], '.1f')}</td>"
                    f"<td>{_num(s['path_dev_mm'], '.1f')}</td><td>{s['peak_cmd_qdot']:.2f}</td></tr>")
    return f"<div class='table-wrap'><table><thead>{head}</thead><tbody>{''.join(body)}</tbody></table></div>"


def trials_table(rows: list) -> str:
    cols = ("method", "task", "start", "demo", "push", "goal_moved", "success", "final_pos_err_m",
            "final_ori_err_deg", "time_to_goal_s", "path_deviation_m", "push_displacement_m", "push_turn_deg",
            "peak_joint_speed_rad_s", "joint_limit_hit")
    fmt = {"final_pos_err_m": ".5f", "final_ori_err_deg": ".2f", "time_to_goal_s": ".1f", "path_deviation_m": ".4f",
           "push_displacement_m": ".3f", "push_turn_deg": ".1f", "peak_joint_speed_rad_s": ".2f"}
    head = "".join(f"<th>{c.replace('_', ' ')}</th>" for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(_num(r[c], fmt.get(c, '')))}</td>" for c in cols)
                   + "</tr>" for r in rows)
    return f"<div class='table-wrap'><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>"


def showcase_html(name: str, case: dict, fig_dir: Path) -> str:
    """The key frames (and clip) of one filmed trial, saved as figures/frames[_pose].png, and their caption."""
    r, rec = case["row"], case["recorder"]
    tag = "_pose" if r["pose"] else ""
    twist = f" and {PUSH_TORQUE:.0f} N m" if r["pose"] else ""
    turn = f", turned {r['goal_turn_deg']:.0f} deg" if r["pose"] else ""
    titles = {"push": f"push {PUSH_FORCE:.0f} N{twist} for {1e3 * PUSH_STEPS / RATE:.0f} ms",
              "goal moved": f"goal moved {1e2 * np.linalg.norm(r['goal_shift_m']):.0f} cm{turn}",
              "end": f"end: {1e3 * r['final_pos_err_m']:.2f} mm, {r['final_ori_err_deg']:.2f} deg from the goal"}
    save_key_frames(rec.frames, titles, r["method"], fig_dir / f"frames{tag}")
    where = f"held-out demo {r['demo']}" if r["demo"] is not None else "a random start"
    turning = (f" The gripper follows the model's angular velocity: the push twisted it by {r['push_turn_deg']:.0f}°, "
               f"the blue bar is the goal orientation's gripper axis." if r["pose"] else
               " The gripper is held pointing down.")
    out = (f"<figure><img src='figures/frames{tag}.png' alt='simulator frames, {html.escape(name)}'><figcaption><b>The "
           f"{r['task']} task, {html.escape(name)} from {where}</b>, rendered by pybullet's TinyRenderer: red line "
           f"the held-out demonstration, the gripper's path so far in the method's colour, red ball the goal. "
           f"Pushed at t = {r['push_time_s']:.1f} s (displaced {1e2 * r['push_displacement_m']:.0f} cm), "
           f"goal moved at t = {r['goal_move_time_s']:.1f} s; within {TOL * 1e3:.0f} mm and {TOL_DEG:g}° of the new "
           f"goal from t = {_num(r['time_to_goal_s'], '.1f')} s.{turning}</figcaption></figure>")
    if rec.clip:
        save_gif(rec.clip, fig_dir / f"trial{tag}.gif", f"{name}, {r['task']}")
        out += (f"<figure><img src='figures/trial{tag}.gif' alt='animated trial, {html.escape(name)}'><figcaption>The "
                "same trial, one frame per 0.5 s played at 10 frames per second (5x real time).</figcaption></figure>")
    return out


def write_page(out_dir, results: dict, paths: dict, demos_of: dict, showcase: dict) -> Path:
    """Figures, frames, clip and ``index.html`` in ``out_dir``."""
    out_dir = Path(out_dir)
    fig_dir = out_dir / "figures"
    rows, meta = results["trials"], results["meta"]
    save_figure(paths_figure(paths, demos_of, rows), fig_dir / "paths", dpi=110)
    save_figure(paths_figure(paths, demos_of, rows, ("PoseCDSP", "GMR pose")), fig_dir / "pose_paths", dpi=110)
    save_figure(angles_figure(paths, rows), fig_dir / "angles", dpi=110)
    parts = [showcase_html(name, case, fig_dir) for name, case in showcase.items()]
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
demonstrations per task, positions in cm, orientations as unit quaternions), mapped into the simulated Panda's base
frame by <code>x_sim = x_cm / 100 + ({shift}) m</code> (orientations as recorded): one translation for all tasks,
placing the centre of their bounding box 0.5 m in front of the robot, 0.3 m above the floor. Every 50th sample is
reachable, pointing down (inverse kinematics error &lt; {1e3 * max(v['down']['max_ik_error_m'] for v in meta['reachability'].values()):.1f} mm,
joints at least {min(v['down']['min_joint_margin_deg'] for v in meta['reachability'].values()):.0f}° from their limits) and with
the recorded orientation (&lt; {1e3 * max(v['recorded']['max_ik_error_m'] for v in meta['reachability'].values()):.1f} mm and
{max(v['recorded']['max_ik_angle_deg'] for v in meta['reachability'].values()):.2f}°, joints at least
{min(v['recorded']['min_joint_margin_deg'] for v in meta['reachability'].values()):.0f}° from their limits).
Models learn from demonstrations 0-{N_TRAIN - 1}; demonstrations {N_TRAIN}-8 give held-out starts.</p>
<p><b>Controller</b> ({meta['rate_hz']:.0f} Hz, the simulator's rate): the model's twist (v, ω) for the current goal
pose; joint velocities by damped least squares on the 6-D Jacobian, joint-limit avoidance in the null space, sent with
<code>VELOCITY_CONTROL</code> at the Panda's torque limits. <b>Position trials</b> (CDSP, GMR): v from the model,
at most {MAX_SPEED} m/s; the gripper held pointing down (ω = 4 e, e the rotation vector to the goal orientation).
<b>Pose trials</b> (PoseCDSP, GMR pose): v and ω from the model (ω = R J_r(r) ṙ, r = log(R_gᵀR)), scaled by one
factor to at most {MAX_SPEED} m/s and {MAX_ANGULAR_SPEED} rad/s. <b>Disturbances</b>: a horizontal push of
{PUSH_FORCE:.0f} N (pose trials: and a torque of {PUSH_TORQUE:.0f} N m about a random axis, twisting the gripper)
for {1e3 * PUSH_STEPS / RATE:.0f} ms on the end effector at a random time
({PUSH_WINDOW[0]:.0%}-{PUSH_WINDOW[1]:.0%} of the demonstrations' duration); the goal moved by
{meta['goal_shift_m'] * 100:.0f} cm in a random direction (pose trials: and turned {GOAL_TURN_DEG:.0f}° about a random
axis) at a random time ({GOAL_WINDOW[0]:.0%}-{GOAL_WINDOW[1]:.0%}). <b>Success</b>: within {TOL * 1e3:.0f} mm and
{TOL_DEG:g}° of the current goal pose at the end of the trial (twice the demonstrations' duration), no joint within
0.5° of a limit. Baselines: GMR (no stability guarantee) through the same controller; for poses, a GMR of the positions
and a GMR of the rotation vector r.</p>
<h2>Trials in the simulator</h2>{''.join(parts)}
<h2>End-effector paths</h2>
<figure><img src="figures/paths.png" alt="3-D paths, position trials"><figcaption>Position trials: paths against the
demonstrations (grey: training, red: held-out); black star the demonstrations' goal, hollow stars moved goals. Axes:
the demonstrations' box grown by {MARGIN * 100:.0f} cm; paths leaving it are cut at its faces.</figcaption></figure>
<figure><img src="figures/pose_paths.png" alt="3-D paths, pose trials"><figcaption>Pose trials: the same for
PoseCDSP and the GMR pose baseline.</figcaption></figure>
<figure><img src="figures/angles.png" alt="angle to the goal orientation"><figcaption>Pose trials: the angle to the
current goal orientation over time (the jumps: a start, a twist, a turned goal); dotted: the {TOL_DEG:g}° success
line.</figcaption></figure>
<h2>Success</h2>{summary_table(rows)}
<h2>Every trial</h2><details><summary>{len(rows)} trials</summary>{trials_table(rows)}</details>
<p class="note">Numbers: <code>results.json</code> (meta and one row per trial). Made by <code>make robot</code>.</p>
</body></html>
"""
    path = out_dir / "index.html"
    path.write_text(page)
    return path

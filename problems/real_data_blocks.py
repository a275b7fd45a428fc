"""What blocks each missed target of ``make real-data`` (issue 21, item 3): numbers and figures.

Per set, from the protocol's own data (:func:`sosdyn.evaluation.realdata.prepare`) and the
default's entry:

* DTWD: copy picks, for each test demo, the training demo nearest *to the whole test demo* (an
  oracle); a model sees only the start. ``start_copy`` is the mean DTWD of the training demo whose
  20th kept sample is nearest to the test start (what copying from the start alone scores),
  ``spread`` the mean DTWD between two training demos; both over copy, next to the model's ratio
  and DMP's (every reproduction read at its demo's period, :func:`sosdyn.evaluation.realdata.at_period`).
* excursion: per test demo the start's own excursion (a lower bound for any model), the
  measured one, the measured one beyond the box widened to hold the start (the target's) and the
  certified bound (:func:`sosdyn.lfd.model.reach.reach_box`).
* arrival: per demo the speed at its last kept sample over its peak speed (a demo cut while
  moving ends fast), and per test reproduction the distance to the goal over time.
* crossings: the training demos' crossings (:func:`sosdyn.lfd.data.crossing.find_crossings`): where
  two paths cross (or one crosses itself) at an angle, no first-order field follows both, certified
  or not (one velocity per state).
* what the certificate forbids (:func:`metric_profiles`, stored in the default's entry): along each
  training demo the metric distance to the goal D = |phi(z)|_M in the certificate's coordinates
  (z = (x - goal) / scale, phi the warp, M the constant metric). Every trajectory of the model has
  D(t) <= D(s) e^{-gamma (t - s) / 2} for s < t (docs/theory.md), whatever its timing: where D rises
  along a demo, no reproduction can follow it there; ``rise`` = max over s < t of D(t) / D(s) while
  D(s) >= RISE_FROM D(0) (the wiggles of a demo settling on its goal left out).

Figures (``<out>/figures/blocks_*.png``): ``blocks_dtwd``, ``blocks_excursion`` and ``blocks_metric`` (all sets),
``blocks_arrival__<set>`` (sets missing the arrival target), ``blocks_starts__<set>`` (sets missing
the excursion target: test starts against the training box and goal). Targets: :data:`TARGETS`.
"""
from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
from matplotlib.patches import Rectangle
from matplotlib.ticker import ScalarFormatter

from sosdyn.evaluation import dsopt, realdata
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.data.crossing import find_crossings
from sosdyn.lfd.fit.composite import apply as warp_apply
from sosdyn.lfd.model.reach import metric_matrix
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import new_figure, styled

DEFAULT = "CDSP default"
CUT_MOVING = 0.1        # a demo "ends while moving" when its last speed exceeds this fraction of its peak
PROFILE_POINTS = 200    # samples kept of each demo's metric-distance profile
RISE_FROM = 0.02        # a rise counts while the distance is still >= this fraction of the demo's first
#: Issue 36's targets: DTWD <= 1.5x copy (and no worse than DMP's), excursion beyond the training box widened to
#: hold the start <= 0.25 of its diagonal, arrival within 2x the demo's remaining duration (and certified).
TARGETS = {"ratio": 1.5, "excursion_beyond_start": 0.25, "arrival_ratio": 2.0}


def set_numbers(demos, entry: dict, dmp: dict | None = None) -> dict:
    """The block numbers of one set (module docstring) for the default's ``entry`` (and DMP's)."""
    _, recorded, test, _ = realdata.prepare(demos)
    copy = entry["copy_mean"]
    starts = np.array([d.pos[dsopt.START_INDEX] for d in recorded])
    nearest = [int(np.argmin(np.linalg.norm(starts - x0, axis=1))) for x0 in dsopt.start_points(test)]
    start_copy = float(np.mean([dtwd(recorded[j].pos, d.pos).total for j, d in zip(nearest, test)]))
    spread = float(np.mean([dtwd(a.pos, b.pos).total for a, b in itertools.combinations(list(recorded), 2)]))
    end_speed = [float(np.linalg.norm(d.vel[-1]) / np.linalg.norm(d.vel, axis=1).max())
                 for d in list(recorded) + list(test)]
    ok = dmp is not None and not (dmp.get("error") or dmp.get("failure"))
    return {"ratio": entry["ratio"], "dmp_ratio": dmp["ratio"] if ok else None, "arrival_ratio": entry["arrival_ratio"],
            "start_copy_ratio": start_copy / copy, "spread_ratio": spread / copy,
            "start_excursion": [t["start_excursion"] for t in entry["tests"]],
            "excursion": [t["excursion"] for t in entry["tests"]],
            "excursion_beyond_start": [t["excursion_beyond_start"] for t in entry["tests"]],
            "excursion_bound": [t["excursion_bound"] for t in entry["tests"]],
            "end_speed": end_speed, "n_train": len(recorded), "crossings": len(find_crossings(recorded)),
            "rise": None if not entry.get("metric_profiles") else [p["rise"] for p in entry["metric_profiles"]],
            "cut_moving": int(sum(v > CUT_MOVING for v in end_speed))}


def metric_profiles(model, demos) -> list[dict] | None:
    """Per demo of ``demos``: its times from 0 (``t``), the metric distance to the goal D (``d``,
    module docstring; at most PROFILE_POINTS samples) and its largest rise max_{s<t} D(t) / D(s)
    (``rise``, from every sample while min_{s<=t} D(s) >= RISE_FROM D(0)); None when the model's metric is
    not constant."""
    M = metric_matrix(model)
    if M is None:
        return None
    out = []
    for d in demos:
        Z = (d.pos - model.goal_) / model.scale_
        U = Z if model.warp_ is None else warp_apply(Z, model.warp_)
        D = np.sqrt(np.maximum(np.einsum("ti,ij,tj->t", U, M, U), 0.0))
        low = np.minimum.accumulate(D)
        far = low >= RISE_FROM * D[0]
        rise = float(np.max(D[far] / low[far])) if D[0] > 0 else 1.0
        keep = np.unique(np.linspace(0, len(D) - 1, min(PROFILE_POINTS, len(D))).astype(int))
        out.append({"t": (d.t[keep] - d.t[0]).tolist(), "d": D[keep].tolist(), "rise": rise})
    return out


@styled
def metric_figure(entries: dict, out_dir: Path) -> dict:
    """One panel per set with profiles (``entries`` {set: the default's entry}): each training demo's
    metric distance to the goal over its first value against time over its duration, the certified
    decay e^{-gamma t / 2} from its start (gamma from the entry), the demo of largest rise drawn dark."""
    names = [s for s, e in entries.items() if e.get("metric_profiles")]
    cols = min(3, len(names))
    fig = new_figure(4.0 * cols, 3.2 * ((len(names) + cols - 1) // cols) + 0.6)
    for k, s in enumerate(names):
        ax = fig.add_subplot((len(names) + cols - 1) // cols, cols, k + 1)
        profiles = entries[s]["metric_profiles"]
        worst = int(np.argmax([p["rise"] for p in profiles]))
        for i, p in enumerate(profiles):
            t, d = np.asarray(p["t"]), np.asarray(p["d"])
            ax.plot(t / t[-1], d / d[0], color="#D55E00" if i == worst else "0.6", lw=1.2 if i == worst else 0.6,
                    zorder=3 if i == worst else 2)
        t, d = np.asarray(profiles[worst]["t"]), np.asarray(profiles[worst]["d"])
        ax.plot(t / t[-1], np.exp(-entries[s]["gamma"] * t / 2), color="black", ls="--", lw=0.8)
        ax.axhline(RISE_FROM, color="0.4", ls=":", lw=0.6)
        ax.set_yscale("log")
        ax.set_title(f"{s.replace('robottasks/', 'rt/')}: rise up to {profiles[worst]['rise']:.2f}x", fontsize=8)
        ax.set_xlabel("t / demo duration", fontsize=7)
        ax.set_ylabel("D(t) / D(0)", fontsize=7)
    fig.suptitle("What the certificate forbids: each training demo's metric distance to the goal D = |phi(z)|_M "
                 f"(grey; largest rise above {RISE_FROM:.0%} of D(0) in red).\nEvery reproduction has D(t) <= D(s) "
                 "exp(-gamma (t - s) / 2) for s < t (dashed: from the red demo's start): it cannot follow a demo "
                 "where D rises", fontsize=8)
    return save_figure(fig, Path(out_dir) / "figures" / "blocks_metric", dpi=110)


@styled
def dtwd_figure(numbers: dict, out_dir: Path) -> dict:
    """Per set: the default's and DMP's DTWD / copy, the nearest-start training demo's and the training
    demos' mutual DTWD over copy, with the target."""
    names = list(numbers)
    fig = new_figure(9.0, 4.0)
    ax = fig.add_subplot(1, 1, 1)
    x = np.arange(len(names))
    for k, (key, label, color) in enumerate((("ratio", "CDSP default", "#0072B2"), ("dmp_ratio", "DMP", "#CC79A7"),
                                             ("start_copy_ratio", "copy the training demo with the nearest start",
                                              "#009E73"),
                                             ("spread_ratio", "mean DTWD between two training demos", "0.6"))):
        ax.bar(x + (k - 1.5) * 0.2, [numbers[s][key] or np.nan for s in names], 0.2, color=color, label=label)
    ax.axhline(TARGETS["ratio"], color="black", ls="--", lw=0.8, label=f"target: {TARGETS['ratio']:g}x copy")
    ax.axhline(1.0, color="black", lw=0.5)
    ax.set_xticks(x, [s.replace("robottasks/", "rt/") for s in names], fontsize=8)
    ax.set_ylabel("test DTWD / copy (nearest demo, oracle)")
    ax.set_yscale("log")
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize=7)
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_formatter(ScalarFormatter())
    fig.suptitle("Test DTWD over copy (copy picks the training demo nearest to the whole test demo; reproductions\n"
                 "read at the demos' period): the default, DMP, copying from the start alone, and the demos' spread",
                 fontsize=9)
    return save_figure(fig, Path(out_dir) / "figures" / "blocks_dtwd", dpi=110)


@styled
def excursion_figure(numbers: dict, out_dir: Path) -> dict:
    """Per set: the worst test demo's start excursion, measured excursion (outside the training box, and
    beyond it widened to hold the start: the target's) and certified bound (bars), every test demo's
    value (dots)."""
    names = list(numbers)
    fig = new_figure(9.0, 4.2)
    ax = fig.add_subplot(1, 1, 1)
    x = np.arange(len(names))
    for k, (key, color, label) in enumerate((("start_excursion", "0.6", "start (no rollout from it does better)"),
                                             ("excursion", "#0072B2", "measured (CDSP default)"),
                                             ("excursion_beyond_start", "#56B4E9", "measured, beyond the start"),
                                             ("excursion_bound", "#D55E00", "certified bound"))):
        values = [[v for v in numbers[s][key] if v is not None] for s in names]
        ax.bar(x + (k - 1.5) * 0.2, [max(v, default=np.nan) for v in values], 0.2, color=color, alpha=0.8,
               label=label + " (worst test demo)")
        for i, v in enumerate(values):
            ax.plot(np.full(len(v), x[i] + (k - 1.5) * 0.2), v, ".", color="black", ms=2.5)
    ax.axhline(TARGETS["excursion_beyond_start"], color="black", ls="--", lw=0.8,
               label=f"target (beyond the start) {TARGETS['excursion_beyond_start']:g}")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_xticks(x, [s.replace("robottasks/", "rt/") for s in names], fontsize=8)
    ax.set_ylabel("excursion / training-box diagonal")
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=7)
    fig.suptitle("Excursion: the test start's own, the rollout's, and the certificate's bound\n"
                 "(bars: worst test demo; dots: every test demo)", fontsize=9)
    return save_figure(fig, Path(out_dir) / "figures" / "blocks_excursion", dpi=110)


def path_times(n_points: int, n_kept: int) -> np.ndarray:
    """Times (s) of the rows :func:`sosdyn.evaluation.realdata.thin` kept of a reproduction of
    ``n_points`` rows (row k at k dt: the start at 0)."""
    idx = np.unique(np.linspace(0, n_points - 1, min(n_kept, n_points)).astype(int))
    return idx * dsopt.DT


@styled
def arrival_figure(name: str, demos, entry: dict, numbers: dict, out_dir: Path) -> dict:
    """Left: each demo's speed at its last kept sample over its peak speed (training, test).
    Right: each test reproduction's distance to the model's goal over the training diagonal against
    time over the test demo's remaining duration, with the arrival radius and the 2x limit."""
    _, recorded, _, _ = realdata.prepare(demos)
    lo, hi, diag = realdata.box(recorded)
    goal = np.asarray(recorded.goal)
    fig = new_figure(10.0, 3.8)
    ax = fig.add_subplot(1, 2, 1)
    v, n = numbers["end_speed"], numbers["n_train"]
    ax.bar(np.arange(n), v[:n], color="0.6", label="training demos")
    ax.bar(np.arange(n, len(v)), v[n:], color="black", label="test demos")
    ax.axhline(CUT_MOVING, color="#D55E00", ls="--", lw=0.8, label=f"{CUT_MOVING:.0%} of peak")
    ax.set_xlabel("demo")
    ax.set_ylabel("speed at the last sample / peak speed")
    ax.set_title(f"{numbers['cut_moving']} of {len(v)} demos end while moving", fontsize=9)
    ax.legend(fontsize=7)
    ax = fig.add_subplot(1, 2, 2)
    for i, (p, t) in enumerate(zip(entry["paths"], entry["tests"])):
        times = path_times(t["n_points"], len(p)) / t["duration_s"]
        ax.plot(times, np.linalg.norm(np.asarray(p) - goal, axis=1) / diag, lw=0.8,
                label="test reproductions" if i == 0 else None, color="#0072B2")
    ax.axhline(0.01, color="black", ls="--", lw=0.8, label="arrival: 1 % of the diagonal")
    ax.axvline(TARGETS["arrival_ratio"], color="#D55E00", ls="--", lw=0.8, label="target: 2x the duration")
    ax.set_yscale("log")
    ax.set_xlabel("time / test demo's remaining duration")
    ax.set_ylabel("distance to the goal / diagonal")
    ax.legend(fontsize=7)
    fig.suptitle(f"{name}: demos cut while moving; reproductions that stall short of the goal before converging",
                 fontsize=9)
    return save_figure(fig, Path(out_dir) / "figures" / f"blocks_arrival__{name.replace('/', '__')}", dpi=110)


@styled
def starts_figure(name: str, demos, entry: dict, out_dir: Path) -> dict:
    """x-y and x-z: training demos, the training box, the goal, the test demos and their starts
    (marked with the start's own excursion) and the default's reproductions."""
    _, recorded, test, _ = realdata.prepare(demos)
    lo, hi, _ = realdata.box(recorded)
    views = [(0, 1), (0, 2)] if demos.dim >= 3 else [(0, 1)]
    fig = new_figure(5.0 * len(views), 4.4)
    for k, (a, b) in enumerate(views):
        ax = fig.add_subplot(1, len(views), k + 1)
        for i, d in enumerate(recorded):
            ax.plot(d.pos[:, a], d.pos[:, b], color="0.7", lw=0.7, label="training demos" if i == 0 else None)
        ax.add_patch(Rectangle((lo[a], lo[b]), hi[a] - lo[a], hi[b] - lo[b], fill=False, ec="0.3", lw=0.8, ls=":",
            label="training box"))
        for i, (d, p, t) in enumerate(zip(test, entry["paths"], entry["tests"])):
            ax.plot(d.pos[:, a], d.pos[:, b], color="black", lw=0.8, ls="--", label="test demos" if i == 0 else None)
            p = np.asarray(p)
            ax.plot(p[:, a], p[:, b], color="#0072B2", lw=1.0, label="CDSP default" if i == 0 else None)
            x0 = d.pos[dsopt.START_INDEX]
            ax.plot(x0[a], x0[b], "o", color="#D55E00", ms=5, label="test starts" if i == 0 else None)
            ax.annotate(f"{t['start_excursion']:.2f}", (x0[a], x0[b]), fontsize=7, xytext=(4, 4),
                        textcoords="offset points")
        ax.plot(recorded.goal[a], recorded.goal[b], "*", color="black", ms=10, label="goal")
        ax.set_xlabel(f"{'xyz'[a]} ({demos.units})")
        ax.set_ylabel(f"{'xyz'[b]} ({demos.units})")
        ax.set_aspect("equal", adjustable="datalim")
    handles, labels = fig.axes[-1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=len(labels), fontsize=7)
    fig.suptitle(f"{name}: test starts (numbers: their own excursion / diagonal) against the training box",
                 fontsize=9)
    return save_figure(fig, Path(out_dir) / "figures" / f"blocks_starts__{name.replace('/', '__')}", dpi=110)


def blocks(entries: dict, load, out_dir: Path, dmp: dict | None = None) -> dict:
    """Numbers and figures for the default's entries ``{set: entry}`` (sets whose entry failed are
    left out) and DMP's (``dmp``, {set: entry}); ``load(set)`` gives the set's demonstrations.
    Returns ``{"numbers", "figures"}`` (figure paths relative to ``out_dir``)."""
    out_dir = Path(out_dir)
    ok = {s: e for s, e in entries.items() if not (e.get("error") or e.get("failure"))}
    numbers = {s: set_numbers(load(s), e, (dmp or {}).get(s)) for s, e in ok.items()}
    rel = lambda paths: str(paths["png"].relative_to(out_dir))          # noqa: E731
    figures = {"dtwd": rel(dtwd_figure(numbers, out_dir)), "excursion": rel(excursion_figure(numbers, out_dir))}
    if any(e.get("metric_profiles") for e in ok.values()):
        figures["metric"] = rel(metric_figure(ok, out_dir))
    for s, e in ok.items():
        if e["arrival_ratio"] > TARGETS["arrival_ratio"]:
            figures[f"arrival {s}"] = rel(arrival_figure(s, load(s), e, numbers[s], out_dir))
        if e["excursion_beyond_start"] > TARGETS["excursion_beyond_start"]:
            figures[f"starts {s}"] = rel(starts_figure(s, load(s), e, out_dir))
    return {"numbers": numbers, "figures": figures}

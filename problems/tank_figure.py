"""The energy-tank figure of docs/theory.md ("Second order"): ``python -m problems tank-figure``.

On ``crossing/at`` (held-out split of :mod:`sosdyn.evaluation.second_order`, data path ``realdata``):
(a) the demos and the reproductions of SecondOrderCDSP (tracking, the default) and of
SecondOrderCDSP(field="mixture") from the test starts; (b) along the tracking reproduction of the first
test demo, V(e) = e^T M e, the tank b and W = V + b (over W(0)) under the certified bound
e^{-2 gamma t}; (c) the mixture's metric: its reproduction's V under the same bound, and the test
demo's own V, which rises above it where the demo gains energy: what a constant metric forbids.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.evaluation import dsopt
from sosdyn.evaluation.second_order import prepare, start_states
from sosdyn.lfd.data.preprocess import smooth
from sosdyn.report.figures import save_figure
from sosdyn.report.figures.style import GOAL_STYLE, new_figure, styled

from .second_order_report import COLORS

OUT = Path(__file__).resolve().parents[1] / "docs" / "images" / "second_order_tank"
SET, DT, SECONDS = "crossing/at", 0.01, 12.0


def energy(model, X, V) -> np.ndarray:
    """V(e) = e^T M e at the rows of X, V (the model's scaled units)."""
    s, T = model.length_scale_, model.time_scale_
    E = np.hstack([(X - model.goal_) / s, V * T / s])
    return np.einsum("ti,ij,tj->t", E, model.M_, E)


def run(model, x0, v0):
    """(X, V, B) of the protocol's semi-implicit Euler from (x0, v0) with a full tank, SECONDS long."""
    X, V = x0[None].astype(float), v0[None].astype(float)
    B = model.initial_tank(X, V)
    rows = []
    for _ in range(int(SECONDS / DT)):
        rows.append((X[0].copy(), V[0].copy(), B[0]))
        A, rate = model.derivatives(X, V, model.goal_, B)
        V = V + DT * A
        X = X + DT * V
        B = np.maximum(0.0, B + DT * rate)
    return tuple(np.array(c) for c in zip(*rows))


@styled
def figure(out: Path = OUT) -> dict:
    demos = sd.load_dataset(SET)
    train, recorded, test, window, _ = prepare(demos, "realdata")
    tracking, mixture = sd.SecondOrderCDSP().fit(train), sd.SecondOrderCDSP(field="mixture").fit(train)
    X0, V0 = start_states(test, window)
    fig = new_figure(15, 4.8)
    ax = fig.add_subplot(1, 3, 1)
    for i, d in enumerate(recorded):
        ax.plot(*d.pos.T, color="0.6", lw=0.9, label="training demos" if i == 0 else None)
    for i, d in enumerate(test):
        ax.plot(*d.pos.T, color="black", lw=0.9, ls="--", label="test demos" if i == 0 else None)
    runs = {}
    for name, model in (("SecondOrderCDSP", tracking), ("SecondOrderCDSP mixture", mixture)):
        for i, (x0, v0) in enumerate(zip(X0, V0)):
            X, V, B = run(model, x0, v0)
            runs[name, i] = (X, V, B)
            ax.plot(*X.T, color=COLORS[name], lw=1.5, label=name if i == 0 else None)
    ax.plot(*train.goal, **GOAL_STYLE)
    ax.set_aspect("equal")
    ax.set_title(f"{SET}: reproductions from the test starts")
    ax.legend(loc="lower left", fontsize=7.5)
    t = np.arange(int(SECONDS / DT)) * DT
    X, V, B = runs["SecondOrderCDSP", 0]
    Vm = energy(tracking, X, V)
    W0 = Vm[0] + B[0]
    ax = fig.add_subplot(1, 3, 2)
    ax.plot(t, Vm / W0, color=COLORS["SecondOrderCDSP"], label="V = eᵀMe")
    ax.plot(t, B / W0, color="#009E73", label="tank b")
    ax.plot(t, (Vm + B) / W0, color="black", label="W = V + b")
    ax.plot(t, np.exp(-2 * tracking.gamma * t), ":", color="0.3", label=r"certified bound $e^{-2\gamma t}$")
    ax.axhline(Vm[0] / W0, color=COLORS["SecondOrderCDSP"], lw=0.6, ls="--")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("÷ W(0)")
    ax.set_title(f"tracking: V rises to {Vm.max() / Vm[0]:.1f}× V(0), paid by the tank (b(0) = {tracking.tank_.beta:.0f} V(0))")
    ax.legend(fontsize=7.5)
    X, V, _ = runs["SecondOrderCDSP mixture", 0]
    Vm = energy(mixture, X, V)
    d = smooth(test[0], window)
    k = dsopt.START_INDEX
    Vd = energy(mixture, d.pos[k:], d.vel[k:])
    ax = fig.add_subplot(1, 3, 3)
    ax.plot(t, Vm / Vm[0], color=COLORS["SecondOrderCDSP mixture"], label="mixture reproduction's V")
    ax.plot(d.t[k:] - d.t[k], Vd / Vd[0], color="black", ls="--", label="the test demo's own V")
    ax.plot(t, np.exp(-2 * mixture.gamma * t), ":", color="0.3", label=r"certified bound $e^{-2\gamma t}$")
    ax.set_yscale("log")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("÷ V(0)")
    ax.set_title(f"mixture (one constant M): the demo's V rises to {Vd.max() / Vd[0]:.0f}× V(0);\n"
                 "every reproduction stays under the bound")
    ax.legend(fontsize=7.5)
    return save_figure(fig, out, dpi=90)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m problems tank-figure", description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, default=OUT, help="output path without suffix (png and svg)")
    args = p.parse_args(list(argv or []))
    paths = figure(args.out)
    print(f"tank-figure: {paths['png']}")
    return 0

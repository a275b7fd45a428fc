"""The diffeomorphic pre-warp on one LASA shape (docs/theory.md): the plain fit, the default's
warped fit, and the training demonstrations in the warped coordinates.

On the ds-opt split (train demos 1-4, test 5-7, every 2nd sample), ``CDSP(warp="none")`` and
``CDSP()`` are fitted on the training demos; each panel draws the field's streamlines, the test
demonstrations (red) and the protocol's Euler reproductions from their 20th points (dashed blue)
with the protocol's test DTWD in the title; the third panel draws the training demonstrations
mapped by the kept warp, x* + s phi((x - x*) / s), along which a constant-metric contracting
field can move (the distance to the goal decreases). Run: ``make warp-figure``
(writes ``docs/images/warp_<shape>.{png,svg}``).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.evaluation import dsopt
from sosdyn.evaluation.metrics import dtwd
from sosdyn.lfd.fit.params import PLAIN
from sosdyn.lfd.fit.warp import apply
from sosdyn.report.figures import save_figure, streamlines
from sosdyn.report.figures.style import new_figure

OUT = Path(__file__).resolve().parents[1] / "docs" / "images"


def warped_curves(model, curves) -> list[np.ndarray]:
    """Each curve (T, n) in the kept warp's coordinates, in the data's units: x* + s phi((x - x*)/s)."""
    w, g, s = model.warp_, model.goal_, model.scale_
    return [g + s * apply((c - g) / s, w["centers"], w["vectors"], w["sigmas"], np.zeros_like(g)) for c in curves]


def figure(shape: str, out_dir: Path) -> dict:
    """Fit both models on ``shape``'s training demos and draw the three panels."""
    train, test = dsopt.split(sd.load_lasa(shape))
    models = {"plain fit": sd.CDSP(**PLAIN).fit(train), "default CDSP()": sd.CDSP().fit(train)}
    fig = new_figure(13.0, 4.6)
    axes = fig.subplots(1, 3)
    scores = {}
    for ax, (label, model) in zip(axes, models.items()):
        field = model.predict
        reps = dsopt.euler_reproduce(field, dsopt.start_points(test))
        scores[label] = float(np.mean([dtwd(r, d.pos).total for r, d in zip(reps, test)]))    # the protocol's score
        streamlines(ax, field, [d.pos for d in test], reps, test.goal,
                    title=f"{shape}, {label}: test DTWD {scores[label]:.0f}")
    default = models["default CDSP()"]
    if default.warp_ is not None:
        for c in warped_curves(default, [d.pos for d in train]):
            axes[2].plot(c[:, 0], c[:, 1], color="#c0392b", lw=1.4)
        axes[2].plot(*default.goal_, "k*", ms=10)
        axes[2].set_title(f"warped training demos ({len(default.warp_['sigmas'])} bumps)")
        axes[2].set_xlabel("$u_1$ (mm)")
        axes[2].set_ylabel("$u_2$ (mm)")
        axes[2].set_aspect("equal", adjustable="datalim")
    else:
        axes[2].set_title("the default kept no warp")
    paths = save_figure(fig, out_dir / f"warp_{shape}")
    return {"scores": scores, "warp_scores": default.warp_scores_, "png": str(paths["png"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m problems warp-figure", description=__doc__.split("\n")[0])
    ap.add_argument("--shape", default="DoubleBendedLine", help="LASA shape (default: %(default)s)")
    ap.add_argument("--out", default=str(OUT), help="output folder (default: docs/images)")
    args = ap.parse_args(argv)
    res = figure(args.shape, Path(args.out))
    print(f"{args.shape}: test DTWD " + ", ".join(f"{k} {v:.0f}" for k, v in res["scores"].items())
          + f"; warp scores {res['warp_scores']}; wrote {res['png']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Fit a certified CDSP model to a LASA handwriting shape and draw its streamlines.

Usage: python 01_lasa_fit_and_plot.py [OUT_DIR]     (default: a new temporary folder)
Needs the `lasa` extra (pip install 'sosdyn[lasa]').
"""
import sys
import tempfile
from pathlib import Path

import sosdyn as sd
from sosdyn.report.figures import save_figure, streamlines

out = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="sosdyn-"))

demos = sd.load_lasa("Leaf_1").subsample(2)          # 7 demos x 500 points, mm
model = sd.CDSP(n_components=6, solver_method="ica", random_state=0).fit(demos)

report = model.verification_                        # Gram check + 10^4 sampled states
print(report)
print(f"certified: {report.passed}")

starts = [d.pos[0] for d in demos]
# twice each demonstration's duration: the default (warped) model may arrive later than the demonstrator
repros = [model.rollout(x0, duration=2 * float(d.t[-1])).pos for x0, d in zip(starts, demos)]
final_errors = [abs(r[-1] - demos.goal).max() for r in repros]
print(f"largest final distance to the goal: {max(final_errors):.2f} mm")

fig = streamlines(None, model.predict, [d.pos for d in demos], repros, demos.goal,
                  title="Leaf_1, CDSP (ICA)")
paths = save_figure(fig, out / "leaf_1_streamlines")
print(f"wrote {paths['png']}")

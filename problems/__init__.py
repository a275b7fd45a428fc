"""The experiments of the sosdyn repository (not part of the installed package).

Run one with ``python -m problems NAME [options]`` (from the repository root), ``make NAME``
or ``sosdyn experiment NAME [--repo DIR] [options]``; :data:`EXPERIMENTS` lists them.
"""
from __future__ import annotations

import importlib
from collections.abc import Sequence

from sosdyn.errors import InputError

#: Experiment name -> the module of this package whose ``main(argv)`` runs it.
EXPERIMENTS = {
    "run": "run",                      # make run: shapes x methods, Figs. 1-4, findings, report
    "report": "report",                # make report: results.json + report from the cache (no fits)
    "fig1": "fig1", "fig2": "fig2", "fig3": "fig3", "fig4": "fig4",
    "lasa-all": "lasa_all",
    "lasa-dsopt": "lasa_dsopt",        # CDSP variants on the LPV-DS (ds-opt) LASA protocol
    "crossing-shapes": "crossing_shapes",   # writes the synthesised hand-drawn crossing set
    "crossing-letters": "crossing_letters",  # writes the held-out crossing letters (another generator)
    "winding-shapes": "winding_shapes",     # writes the synthesised hand-drawn winding set
    "winding": "winding",              # held-out accuracy on the winding set (issue 36)
    "second-order": "second_order",    # first- against second-order CDSP: crossing shapes and LASA
    "tank-figure": "tank_figure",      # the energy tank on crossing/at (docs/theory.md's figure)
    "real-data": "real_data",          # held-out accuracy on the shipped real demonstration sets
    "real-data-configs": "real_data_configs",   # CDSP configurations on the real sets' training data
    "lasa-dsopt-report": "lasa_dsopt_report",   # its pages redrawn from results.json (no fits)
    "warp-figure": "warp_figure",      # the pre-warp on DoubleBendedLine (docs/theory.md's figure)
    "demo3d": "demo3d",
    "demo7d": "demo7d",                # a certified CDSP from 5 noisy 7-D joint-space demonstrations
    "kinks7d": "kinks7d",              # peak accelerations of 7-D reproductions, plain and tempered gating
    "robot": "robot",                  # CDSP drives a simulated Panda (pybullet; the [robot] extra)
    "sweep": "sweep",                  # a hyper-parameter sweep (joblib processes, or a Dask cluster)
    "learner-table": "learner_table",
    "poses": "poses",                  # certified pose models on the robottasks Franka demos
    "bench": "bench.learner",          # where the CDSP learner spends its time
    "bench-sos": "bench.sos",          # the SOS layer against SumOfSquares
}


def run_experiment(name: str, argv: Sequence[str] = ()) -> int:
    """Run experiment ``name`` ("lasa-all" or "lasa_all") with command-line ``argv``; its exit code."""
    key = name.replace("_", "-")
    if key not in EXPERIMENTS:
        raise InputError(f"no experiment {name!r}; available: {', '.join(EXPERIMENTS)}. "
                         "Try: one of those names.")
    # By name: an experiment's (heavy) imports load only when it runs.
    module = importlib.import_module(f"{__name__}.{EXPERIMENTS[key]}")
    return module.main(list(argv)) or 0

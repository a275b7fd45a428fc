"""CDSP configurations on the real sets, scored on TRAINING reproductions (what a choice of default
may use) and, for the record, on the held-out test demos (``python -m problems real-data-configs``).

Per set (problems.real_data.SETS) and configuration (:data:`CONFIGS`): the protocol's training data
(:func:`sosdyn.evaluation.realdata.prepare`), one fit, then reproductions from the training demos'
own 20th kept samples (train DTWD mean, worst arrival ratio and excursion) and from the test demos'
(DTWD / copy, worst arrival ratio and excursion). Writes ``<out>/configs.json`` (default
``reports/real_data``); ~5 min on a loaded 2-core machine, no cache.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import sosdyn as sd
from sosdyn.errors import SosdynError
from sosdyn.evaluation import realdata
from sosdyn.lfd.fit.params import PLAIN

from .jsonio import write_json
from .real_data import OUT, SETS, load

CONFIGS = {"default": {}, "plain": PLAIN, "K4": {"n_components": 4}, "K12": {"n_components": 12},
           "g0.5": {"gamma": 0.5}, "g1": {"gamma": 1.0}, "g0.02": {"gamma": 0.02},
           # one fixed warp instead of the auto choice: the default's 100-map setting, and one matched to
           # every training demo instead of their mean (the real sets' demos differ more than LASA's)
           "warp100": {"warp": {"n_maps": 100, "decay": 0.75}},
           "warp-each": {"warp": {"n_maps": 60, "decay": 1.0, "match": "each"}}}


def scores(model, recorded, curves) -> dict:
    """Reproductions of ``model`` from ``curves``' 20th kept samples: mean DTWD, mean copy, worst
    arrival ratio and excursion (sosdyn.evaluation.realdata.test_scores)."""
    rows = realdata.test_scores(realdata.reproduce(model.predict, recorded, curves), recorded, curves, model.goal_)
    return {"dtwd": float(np.mean([r["dtwd"] for r in rows])), "copy": float(np.mean([r["copy"] for r in rows])),
            "arrival_ratio": max(r["arrival_ratio"] for r in rows), "excursion": max(r["excursion"] for r in rows)}


def run(sets=SETS, configs=tuple(CONFIGS), out_dir=OUT) -> Path:
    out = {}
    for name in sets:
        train, recorded, test, _ = realdata.prepare(load(name))
        for c in configs:
            t0 = time.perf_counter()
            try:
                model = sd.CDSP(**CONFIGS[c]).fit(train)
            except SosdynError as exc:
                out[f"{name}|{c}"] = {"error": f"{type(exc).__name__}: {str(exc).splitlines()[0][:200]}"}
                print(f"{name:32} {c:8} FAILED {out[f'{name}|{c}']['error'][:100]}", flush=True)
                continue
            row = {"fit_s": time.perf_counter() - t0, "certified": bool(model.certified_),
                   "train": scores(model, recorded, recorded), "test": scores(model, recorded, test)}
            out[f"{name}|{c}"] = row
            tr, te = row["train"], row["test"]
            print(f"{name:32} {c:8} train DTWD {tr['dtwd']:9.2f} arrival {tr['arrival_ratio']:5.2f} | test DTWD/copy "
                  f"{te['dtwd'] / te['copy']:5.2f} arrival {te['arrival_ratio']:5.2f} excursion {te['excursion']:.3f}",
                  flush=True)
    return write_json(Path(out_dir) / "configs.json", {"configs": CONFIGS, "results": out})


def main(argv=None):
    p = argparse.ArgumentParser(prog="python -m problems real-data-configs", description=__doc__.split("\n")[0])
    p.add_argument("--sets", nargs="*", default=None, choices=SETS)
    p.add_argument("--configs", nargs="*", default=None, choices=tuple(CONFIGS))
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(list(argv or []))
    print(f"real-data-configs: {run(args.sets or SETS, args.configs or tuple(CONFIGS), args.out)}")
    return 0

"""Single-state prediction for control loops: ``model.predict(x[None])`` against ``model.predictor()(x)``
and the Python export's ``predict(x)`` (:func:`sosdyn.lfd.runtime.export_python.to_python`).

Fits one LASA shape (K = 8, 2-D, linear fields: one plain fit and the default's warped model;
``--cubic`` adds a plain degree-3 model), then times
one call at a time (median over ``--calls`` calls, each timed alone, after a warm-up) at states
along the demonstrations, and checks that both give the same velocities: the largest relative
difference |v_fast - v| / max(|v|, tiny) over the rows of a 10^4-state grid twice the data's box.
Also times ``load_model`` of a maximal legal warp (MAX_MAPS bumps of Lipschitz number 2.7e-3, wide
sigma = 0.5 and tiny sigma = 1e-3, forged onto the plain model with its checksum recomputed; issue 23
item 3: 14-37 s before the load-time check touched only the states a bump moves).
Writes ``reports/bench/predict.json``. Run: ``python -m problems.bench.predict [--quick]``.
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from sosdyn import CDSP, load_lasa
from sosdyn.lfd.fit.params import PLAIN
from sosdyn.lfd.fit.warp import LIP_FACTOR, MAX_MAPS
from sosdyn.lfd.model.fileformat import _digest
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.runtime.export_python import to_python

from ..settings import BENCH
from .timing import environment, median, write_json

TARGET_S = 10e-6                    # issue 26 item 3: predictor() per state, K = 8, 2-D
SPEEDUP_TARGET = 3.0                # predictor() against predict(x[None]) on one state (once a unit test)


def time_calls(f, states, calls: int) -> float:
    """Median seconds of one call f(x), each call timed on its own (after 50 warm-up calls)."""
    for x in states[:50]:
        f(x)
    ts = []
    for i in range(calls):
        x = states[i % len(states)]
        t0 = time.perf_counter()
        f(x)
        ts.append(time.perf_counter() - t0)
    return median(ts)


def grid_states(X: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """``count`` uniform states in the data's bounding box doubled about its centre."""
    lo, hi = X.min(axis=0), X.max(axis=0)
    mid, half = (lo + hi) / 2, (hi - lo)
    return mid + np.random.default_rng(seed).uniform(-1, 1, (count, X.shape[1])) * half


def measure(shape: str, field_degree: int, calls: int, states: int, warp: str = "none") -> dict:
    """Fit ``shape`` (one plain fit, or with ``warp="auto"`` the default's choice of warp) and compare
    the two evaluators (timings in seconds, error relative)."""
    demos = load_lasa(shape)
    model = CDSP(**dict(PLAIN, n_components=8, field_degree=field_degree, random_state=0, warp=warp)).fit(demos)
    X = np.vstack([d.pos for d in demos])
    fast = model.predictor()
    along = X[:: max(1, len(X) // 500)]
    t_batch = time_calls(lambda x: model.predict(x[None])[0], along, calls)
    t_fast = time_calls(fast, along, calls)
    exported: dict = {}
    exec(to_python(model), exported)         # the generated module, as a user imports it
    t_export = time_calls(exported["predict"], along, calls)
    G = grid_states(X, states)
    V = model.predict(G)
    F = np.array([fast(x) for x in G])
    rel = np.abs(F - V).max(axis=1) / np.maximum(np.abs(V).max(axis=1), np.finfo(float).tiny)
    K, n, m = model.C_.shape
    bumps = 0 if model.warp_ is None else len(model.warp_["sigmas"])
    return {"shape": shape, "K": K, "n": n, "monomials": m, "field_degree": field_degree, "warp_bumps": bumps,
            "predict_s": t_batch, "predictor_s": t_fast, "speedup": t_batch / t_fast,
            "python_export_s": t_export, "export_over_predictor": t_export / t_fast,
            "max_rel_diff": float(rel.max()), "states_checked": states, "calls_timed": calls,
            "within_target": bool(t_fast <= TARGET_S), "speedup_met": bool(t_batch >= SPEEDUP_TARGET * t_fast)}


def max_warp_load_s(model, sigma: float, seed: int = 0) -> float:
    """Seconds to ``load_model`` ``model`` carrying MAX_MAPS bumps of width ``sigma`` (z-units), centres
    uniform in |z|_inf <= 2, each of Lipschitz number 2.7e-3 (prod (1 - l_j) = 1.8e-12 >= the floor)."""
    rng = np.random.default_rng(seed)
    C, V = rng.uniform(-2, 2, (MAX_MAPS, model.dim_)), rng.normal(size=(MAX_MAPS, model.dim_))
    V *= (2.7e-3 * sigma / LIP_FACTOR / np.linalg.norm(V, axis=1))[:, None]
    with tempfile.TemporaryDirectory() as tmp:
        path = model.save(Path(tmp) / "m.json")
        data = json.loads(path.read_text())
        data["state"]["warp_"] = {"centers": C.tolist(), "vectors": V.tolist(), "sigmas": [sigma] * MAX_MAPS}
        data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
        path.write_text(json.dumps(data))
        t0 = time.perf_counter()
        load_model(path)
        return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m problems.bench.predict", description=__doc__.split("\n")[0])
    ap.add_argument("--shape", default="Angle", help="LASA shape (default: %(default)s)")
    ap.add_argument("--calls", type=int, default=20000, help="timed calls per evaluator (default: %(default)s)")
    ap.add_argument("--states", type=int, default=10000, help="states of the equality check (default: %(default)s)")
    ap.add_argument("--cubic", action="store_true", help="also a degree-3 field")
    ap.add_argument("--quick", action="store_true", help="1000 calls, 1000 states (smoke test)")
    ap.add_argument("--out", default=str(BENCH), help="output folder (default: reports/bench)")
    args = ap.parse_args(argv)
    calls, states = (1000, 1000) if args.quick else (args.calls, args.states)
    rows = [measure(args.shape, 1, calls, states), measure(args.shape, 1, calls, states, warp="auto")]
    plain = CDSP(**dict(PLAIN, n_components=8, random_state=0, warp="none")).fit(load_lasa(args.shape))
    loads = {f"sigma {s:g}": max_warp_load_s(plain, s) for s in (0.5, 1e-3)}
    print(f"load_model with {MAX_MAPS} bumps: " + ", ".join(f"{k}: {v:.2f} s" for k, v in loads.items()), flush=True)
    if args.cubic:
        rows.append(measure(args.shape, 3, calls, states))
    for r in rows:
        print(f"{r['shape']} K={r['K']} n={r['n']} degree {r['field_degree']}, {r['warp_bumps']} warp bumps: predict {r['predict_s'] * 1e6:.0f} us, "
              f"predictor {r['predictor_s'] * 1e6:.1f} us ({r['speedup']:.0f}x; goal {TARGET_S * 1e6:.0f} us), "
              f"Python export {r['python_export_s'] * 1e6:.1f} us ({r['export_over_predictor']:.1f}x the predictor), "
              f"max rel diff {r['max_rel_diff']:.1e} on {r['states_checked']} states", flush=True)
    path = write_json(Path(args.out) / "predict.json",
                      {"target_s": TARGET_S, "speedup_target": SPEEDUP_TARGET, "rows": rows, "max_warp_load_s": loads,
                       "environment": environment()})
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

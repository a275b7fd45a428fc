"""JSON of the experiments: the one cleaner (numpy to Python), rounding, and writing files."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np


def jsonable(obj, *, finite_only: bool = False):
    """``obj`` with numpy scalars/arrays turned into Python values (dict keys as strings).

    Non-finite floats stay (written as NaN/Infinity, which Python's json reads back) unless
    ``finite_only``: then they become None, for strict JSON readers (the benchmarks).
    """
    if isinstance(obj, dict):
        return {str(k): jsonable(v, finite_only=finite_only) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v, finite_only=finite_only) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist(), finite_only=finite_only)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return None if finite_only and not math.isfinite(value) else value
    return obj


def rounded(arr, digits: int = 5) -> list:
    """An array as nested lists of floats with ``digits`` significant digits (small JSON);
    non-finite values become None."""
    a = np.asarray(arr, dtype=float)
    flat = [float(f"{v:.{digits}g}") if math.isfinite(v) else None for v in a.ravel()]
    return np.array(flat, dtype=object).reshape(a.shape).tolist()


def write_json(path: Path, obj, *, finite_only: bool = False) -> Path:
    """Write :func:`jsonable` ``(obj)`` to ``path`` (folders created), indented."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(jsonable(obj, finite_only=finite_only), indent=1,
                               allow_nan=not finite_only) + "\n")
    return path

"""Global identifiers of scalar decision variables, and the names they print with.

Polynomial coefficients may be affine in decision variables. The polynomial layer only
knows each decision variable by an integer id; which program owns it, and how it is
lowered to a solver, is the SOS layer's business. ``allocate(count, name)`` records the
name of the block: a single id prints as ``name``, the k-th of several as ``name[k]``, an
unnamed id as ``d<id>`` (:func:`decision_name`).
"""
from __future__ import annotations

import bisect
import threading

import numpy as np

_lock = threading.Lock()
_next = 0
_starts: list = []          # first id of every named block (increasing)
_blocks: list = []          # (count, name) of each


def allocate(count: int, name: str | None = None) -> np.ndarray:
    """Reserve ``count`` fresh, consecutive decision ids (named ``name`` when printed)."""
    global _next
    with _lock:
        start = _next
        _next += int(count)
        if name is not None and count:
            _blocks.append((int(count), str(name)))     # before _starts: readers take no lock
            _starts.append(start)
    return np.arange(start, start + int(count), dtype=np.int64)


def decision_name(i: int) -> str:
    """How decision id ``i`` prints: its block's name (``name[k]`` in a block of several), else d<i>."""
    k = bisect.bisect_right(_starts, int(i)) - 1
    if k >= 0:
        count, name = _blocks[k]
        offset = int(i) - _starts[k]
        if offset < count:
            return name if count == 1 else f"{name}[{offset}]"
    return f"d{int(i)}"

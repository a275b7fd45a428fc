"""Global identifiers of scalar decision variables.

Polynomial coefficients may be affine in decision variables. The polynomial layer only
knows each decision variable by an integer id; which program owns it, and how it is
lowered to a solver, is the SOS layer's business.
"""
from __future__ import annotations

import threading

import numpy as np

_lock = threading.Lock()
_next = 0


def allocate(count: int) -> np.ndarray:
    """Reserve ``count`` fresh, consecutive decision ids."""
    global _next
    with _lock:
        start = _next
        _next += int(count)
    return np.arange(start, start + int(count), dtype=np.int64)

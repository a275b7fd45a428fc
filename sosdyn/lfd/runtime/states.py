"""States handed to a fitted model at run time: checked before any arithmetic, and the speed limit.

Every public entry point that takes states (``CDSP.predict``, ``CDSP.rollout``, the one-state
predictor, their ``goal`` arguments) reads them with :func:`as_states`: a real (integer or
float) array of the model's dimension, finite; strings, ragged lists, dicts, None and complex
numbers are an InputError with a hint, never numpy's ValueError / TypeError or a silent cast.

Speed limit: :func:`limit_speed` scales each velocity by the positive factor
``min(1, v_max / |xdot|)``, so |xdot| <= v_max and the direction is kept; ``docs/theory.md``
says why the certificate's convergence survives it (the same paths, traversed more slowly).
"""
from __future__ import annotations

import numpy as np

from sosdyn.errors import InputError
from ..rollout.events import is_positive_number

_REAL_KINDS = "iuf"           # numpy dtype kinds of a state: signed / unsigned integers, floats


def _why_not_numbers(value, arr) -> str:
    if isinstance(value, (str, bytes)):
        return (f"is the text {value!r:.40}, not numbers. Try: numbers, e.g. [1.0, 2.0], or parse the "
                "text first (np.array([float(v) for v in text.split(',')])).")
    if isinstance(value, dict):
        return "is a dict. Try: the values in the order of the model's dimensions, e.g. [d['x'], d['y']]."
    if arr is None or arr.dtype.kind == "O":
        return (f"is not a rectangular array of numbers (a {type(value).__name__} whose rows differ in "
                "length, or hold None / other objects). Try: n numbers, or m rows of n numbers each.")
    if arr.dtype.kind == "c":
        return "has complex entries; states are real. Try: the real parts (np.real(x)) if the imaginary parts are 0."
    if arr.dtype.kind == "b":
        return "holds booleans, not coordinates. Try: numbers."
    return f"holds {arr.dtype} values, not numbers. Try: an array of floats."


def as_states(value, dim: int, what: str = "X") -> np.ndarray:
    """``value`` as a finite float array (m, dim): one state (dim,) becomes (1, dim).

    InputError (with a hint) for text, dicts, ragged or object arrays, booleans, complex
    numbers, a wrong shape, NaN or inf."""
    try:
        arr = None if isinstance(value, (str, bytes, dict)) else np.asarray(value)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.dtype.kind not in _REAL_KINDS:
        raise InputError(f"{what} {_why_not_numbers(value, arr)}")
    arr = arr.astype(float)
    arr = arr[None, :] if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InputError(f"{what} must have shape ({dim},) or (m, {dim}), got {np.shape(value)}. "
                         f"Try: {dim} coordinates per state.")
    if not np.isfinite(arr).all():
        raise InputError(f"{what} contains NaN or inf. Try: finite coordinates.")
    return arr


def as_state(value, dim: int, what: str = "x") -> np.ndarray:
    """``value`` as one finite state of shape (dim,) (:func:`as_states`, exactly one row)."""
    arr = as_states(value, dim, what)
    if np.ndim(value) != 1:
        raise InputError(f"{what} must be one state of shape ({dim},), got shape {np.shape(value)}. "
                         "Try: model.predict(X) for many states at once.")
    return arr[0]


def check_max_speed(max_speed, what: str = "max_speed", unit: str = "data units per second") -> float | None:
    """``max_speed``: None (no limit) or a finite number > 0 (``unit``); InputError naming ``what``."""
    if max_speed is None:
        return None
    if not is_positive_number(max_speed):
        raise InputError(f"{what} must be a finite number > 0 ({unit}) or None, got {max_speed!r}.")
    return float(max_speed)


def speed_factor(V: np.ndarray, max_speed: float | None) -> np.ndarray:
    """min(1, max_speed / |v|) of each row v of V (shape V.shape[:-1] + (1,)); 1 without a limit."""
    speed = np.linalg.norm(V, axis=-1, keepdims=True)
    if max_speed is None:
        return np.ones_like(speed)
    with np.errstate(divide="ignore"):
        return np.minimum(1.0, max_speed / speed)


def limit_speed(V: np.ndarray, max_speed: float | None) -> np.ndarray:
    """The rows of V scaled by min(1, max_speed / |v|): same directions, |v| <= max_speed."""
    return V if max_speed is None else V * speed_factor(V, max_speed)


def as_levels(tank, m: int) -> np.ndarray:
    """Tank levels (m,) from a number or m numbers, each finite and >= 0 (else InputError)."""
    b = np.broadcast_to(np.asarray(tank, dtype=float), (m,)) if np.ndim(tank) == 0 else np.asarray(tank, dtype=float)
    if b.shape != (m,) or not np.isfinite(b).all() or (b < 0).any():
        raise InputError(f"tank must be a number or {m} numbers, finite and >= 0, got shape {np.shape(tank)}. "
                         "Try: tank=None (a full tank: motions starting at these states).")
    return b

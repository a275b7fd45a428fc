"""States handed to a fitted model at run time: checked before any arithmetic, and the speed limit.

Every public entry point that takes states (``CDSP.predict``, ``CDSP.rollout``, the one-state
predictor, their ``goal`` arguments) reads them with :func:`as_states`: a real (integer or
float) array of the model's dimension, finite; strings, ragged lists, dicts, None and complex
numbers are an InputError with a hint, never numpy's ValueError / TypeError or a silent cast.

Speed limit, the one home of its formula (every path -- rollouts, the predictors, the Python and
C++ exports, the pose model -- runs these functions or code generated from this module). With
rho = |xdot| / v_max and a = :data:`SPEED_KNEE`, the limited velocity is lambda(rho) xdot,

    lambda(rho) = sigma(rho) / rho,   sigma(rho) = rho                              (rho <= a)
                                      sigma(rho) = a + (1 - a) y / (1 + y^4)^(1/4),  y = (rho - a) / (1 - a),

so |lambda xdot| = v_max sigma(rho) < v_max, the direction is kept, velocities slower than a v_max are
not changed at all, and sigma is increasing and four times continuously differentiable (y / (1 +
y^4)^(1/4) = y - y^5/4 + ...): no kink for an integrator to stall on (the former min(1, v_max /
|xdot|) is only continuous). |xdot| is computed as m |xdot / m|, m = max_i |xdot_i| (scaled before
squaring), so a velocity of 1e200 is limited, not squared to inf (which made lambda = 0: a rest point
off the goal). ``docs/theory.md`` says why the certificate's convergence survives it: lambda is
positive and continuous, a time change (the same paths, traversed more slowly).
"""
from __future__ import annotations

import math

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


#: Velocities slower than SPEED_KNEE x max_speed are not changed by the speed limit (module docstring).
SPEED_KNEE = 0.5


def saturated_speed(rho: float) -> float:
    """sigma(rho) of the module docstring for one ratio rho = |xdot| / v_max >= 0 (plain floats;
    rho = inf gives 1): the limited speed over v_max."""
    a = SPEED_KNEE
    if rho <= a:
        return rho
    y = (rho - a) / (1.0 - a)
    y2 = y * y
    psi = y / math.sqrt(math.sqrt(1.0 + y2 * y2)) if y <= 1.0 else 1.0 / math.sqrt(math.sqrt(1.0 + 1.0 / (y2 * y2)))
    return a + (1.0 - a) * psi


def limit_speed_one(v: list, max_speed: float) -> list:
    """The velocity v (plain floats) under the speed limit (module docstring): v itself when
    |v| <= SPEED_KNEE max_speed, else the direction v / |v| times max_speed sigma(|v| / max_speed)."""
    m = max(map(abs, v))
    if not m > 0.0:
        return v
    u = [a / m for a in v]
    q = math.sqrt(sum(a * a for a in u))              # |v| = m q, q in [1, sqrt(n)]
    rho = (m / max_speed) * q
    if rho <= SPEED_KNEE:
        return v
    f = max_speed * saturated_speed(rho) / q
    return [a * f for a in u]


def speed_ratio(V: np.ndarray, max_speed: float) -> np.ndarray:
    """|v| / max_speed of each row v of V (shape V.shape[:-1]), scaled before squaring: (m / max_speed)
    |v / m| with m = max_i |v_i|, finite for every finite v (module docstring)."""
    A = np.abs(np.asarray(V, dtype=float))
    m = A.max(axis=-1, keepdims=True)
    with np.errstate(over="ignore"):
        return (m[..., 0] / max_speed) * np.sqrt(((A / np.where(m > 0, m, 1.0)) ** 2).sum(axis=-1))


def saturated_speeds(rho: np.ndarray) -> np.ndarray:
    """sigma(rho) of the module docstring, elementwise (:func:`saturated_speed` on arrays; inf gives 1)."""
    rho = np.asarray(rho, dtype=float)
    a = SPEED_KNEE
    y = np.maximum(rho - a, 0.0) / (1.0 - a)
    with np.errstate(over="ignore", divide="ignore"):
        y2 = y * y
        psi = np.where(y <= 1.0, y / np.sqrt(np.sqrt(1.0 + np.minimum(y2, 1.0) ** 2)),
                       1.0 / np.sqrt(np.sqrt(1.0 + 1.0 / (y2 * y2))))
    return np.where(rho <= a, rho, a + (1.0 - a) * psi)


def saturation_factor(rho: np.ndarray) -> np.ndarray:
    """lambda(rho) = sigma(rho) / rho of the module docstring, elementwise (1 for rho <= SPEED_KNEE)."""
    rho = np.asarray(rho, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rho <= SPEED_KNEE, 1.0, saturated_speeds(rho) / rho)


def joint_ratio(ratios) -> np.ndarray:
    """One ratio for several limits at once (a pose's |v| / v_max and |omega| / w_max): the 4-norm of
    the given ones (None: no limit), scaled by their largest; it is >= each, so lambda of it keeps every
    limit, and it is smooth where the largest of them is (no min of two factors: no kink)."""
    given = [np.asarray(r, dtype=float) for r in ratios if r is not None]
    if not given:
        return np.zeros(())
    m = np.maximum.reduce(given)
    safe = np.where(m > 0, m, 1.0)
    return m * np.sqrt(np.sqrt(sum(((r / safe) ** 2) ** 2 for r in given)))


def speed_factor(V: np.ndarray, max_speed: float | None) -> np.ndarray:
    """lambda of each row v of V (shape V.shape[:-1] + (1,)): the positive factor of the speed limit
    (module docstring), 1 without a limit."""
    V = np.asarray(V, dtype=float)
    if max_speed is None:
        return np.ones(V.shape[:-1] + (1,))
    return saturation_factor(speed_ratio(V, max_speed))[..., None]


def limit_speed(V: np.ndarray, max_speed: float | None) -> np.ndarray:
    """The rows of V under the speed limit (module docstring; :func:`limit_speed_one` row by row): rows
    slower than SPEED_KNEE max_speed unchanged, the others along V / |V| at max_speed sigma(|V| / max_speed)."""
    if max_speed is None:
        return V
    V = np.asarray(V, dtype=float)
    m = np.abs(V).max(axis=-1, keepdims=True)
    U = V / np.where(m > 0, m, 1.0)
    q = np.sqrt((U * U).sum(axis=-1, keepdims=True))             # |V| = m q
    with np.errstate(over="ignore"):
        rho = (m / max_speed) * q
    fast = rho > SPEED_KNEE
    return np.where(fast, U * (max_speed * saturated_speeds(rho) / np.where(fast, q, 1.0)), V)


#: The speed limit in C++ (emitted into every header of :mod:`.export_cpp`): the same operations as
#: :func:`speed_ratio`, :func:`saturated_speed`, :func:`limit_speed_one` and :func:`joint_ratio`.
CPP_SPEED_LIMIT = f"""// The speed limit (sosdyn.lfd.runtime.states): rho = |v| / max_speed, v unchanged for rho <= speed_knee,
// else along v / |v| at the speed max_speed * saturated_speed(rho) < max_speed (smooth in rho).
constexpr double speed_knee = {SPEED_KNEE!r};

inline double saturated_speed(double rho) {{
  if (rho <= speed_knee) return rho;
  const double y = (rho - speed_knee) / (1.0 - speed_knee);
  const double y2 = y * y;
  const double psi = y <= 1.0 ? y / std::sqrt(std::sqrt(1.0 + y2 * y2)) : 1.0 / std::sqrt(std::sqrt(1.0 + 1.0 / (y2 * y2)));
  return speed_knee + (1.0 - speed_knee) * psi;
}}

// |v| / max_speed of v (n doubles) as (m / max_speed) |v / m|, m = max |v_i| (no overflow); q = |v / m|.
inline double speed_ratio(const double* v, int n, double max_speed, double& m, double& q) {{
  m = 0.0;
  q = 0.0;
  for (int i = 0; i < n; ++i) m = std::fabs(v[i]) > m ? std::fabs(v[i]) : m;
  if (!(m > 0.0)) return 0.0;
  for (int i = 0; i < n; ++i) q += (v[i] / m) * (v[i] / m);
  q = std::sqrt(q);
  return (m / max_speed) * q;
}}

// v (n doubles) under the speed limit, in place.
inline void limit_speed(double* v, int n, double max_speed) {{
  double m, q;
  const double rho = speed_ratio(v, n, max_speed, m, q);
  if (rho <= speed_knee) return;
  const double f = max_speed * saturated_speed(rho) / q;
  for (int i = 0; i < n; ++i) v[i] = (v[i] / m) * f;
}}

// The factor lambda = saturated_speed(rho) / rho of the joint ratio of two limits (the 4-norm of a and b).
inline double joint_factor(double a, double b) {{
  const double m = a > b ? a : b;
  if (!(m > 0.0)) return 1.0;
  const double ra = a / m, rb = b / m;
  const double rho = m * std::sqrt(std::sqrt(ra * ra * ra * ra + rb * rb * rb * rb));
  return rho <= speed_knee ? 1.0 : saturated_speed(rho) / rho;
}}
"""


def as_levels(tank, m: int) -> np.ndarray:
    """Tank levels (m,) from a number or m numbers, each finite and >= 0 (else InputError)."""
    b = np.broadcast_to(np.asarray(tank, dtype=float), (m,)) if np.ndim(tank) == 0 else np.asarray(tank, dtype=float)
    if b.shape != (m,) or not np.isfinite(b).all() or (b < 0).any():
        raise InputError(f"tank must be a number or {m} numbers, finite and >= 0, got shape {np.shape(tank)}. "
                         "Try: tank=None (a full tank: motions starting at these states).")
    return b

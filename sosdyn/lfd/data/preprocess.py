"""Preprocessing of recorded demonstrations: resample, trim rest, smooth, align the ends.

:func:`preprocess` runs the four steps in this order; each step's default is chosen from the
demonstrations it is given (pass only training demonstrations, so no test data leaks in):

1. **resample** irregular time stamps (a step off the median step by more than
   :data:`IRREGULAR_TOL`) onto a uniform grid with the median step (linear interpolation).
2. **trim rest**: drop the samples at the start before the motion leaves a ball of radius
   ``tol`` around the first sample (the last resting sample is kept), and those at the end
   after it enters the ball of radius ``tol`` around the last sample for good (the first
   resting one is kept, so the end moves by at most ``tol``); ``tol`` = :data:`REST_NOISE` x
   the noise level sigma (exact repeats only when sigma = 0).
3. **smooth** (Savitzky-Golay, cubic, :func:`scipy.signal.savgol_filter`): positions and
   velocities from the same local cubic fit over w samples. ``"auto"`` estimates the noise
   sigma (:func:`noise_level`) and the typical step ``h`` (median sample-to-sample distance,
   i.e. speed x sampling step): off when sigma / h <= :data:`SMOOTH_OFF_RATIO` (already
   smooth data, e.g. LASA 1e-4, the robottasks sets 1e-3), else the smallest odd w >= 5 whose
   derivative filter ``c_w`` passes noise sigma ||c_w|| <= :data:`VEL_NOISE` x h (velocity
   noise below 2 % of the typical speed), at most a quarter of the shortest demonstration.
4. **align ends**: translate each demonstration by ``w(t) (g - x_i(T_i))``, g the mean end,
   ``w`` a smoothstep from 0 to 1 over the last :data:`BLEND_FRACTION` of its duration (the
   velocities get ``w'(t) (g - x_i(T_i))``); every shift is reported. ``"auto"`` aligns when
   the ends spread more than :data:`ALIGN_MIN` of the bounding-box diagonal (LASA's spread is
   0); ends farther than ``max_shift`` (default :data:`ALIGN_MAX` of the diagonal) from g are
   refused: they are not one task.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.demonstrations import MIN_SAMPLES, Demonstration, Demonstrations, end_distances
from sosdyn.limits import check_bytes

IRREGULAR_TOL = 0.01      # relative deviation of a time step from the median step that triggers resampling
REST_NOISE = 5.0          # rest ball radius, in noise sigmas
SMOOTH_OFF_RATIO = 0.01   # noise / typical step at or below which data count as smooth
VEL_NOISE = 0.02          # target velocity noise / typical step of the smoothing window
SG_ORDER, MIN_WINDOW = 3, 5
GRID_BYTES_PER_VALUE = 32   # working memory of a resampled demo per number (t, x, velocity estimate, copies)
ALIGN_MIN, ALIGN_MAX, BLEND_FRACTION = 0.01, 0.25, 0.5


def _diagonal(demos) -> float:
    pos = np.vstack([d.pos for d in demos])
    return float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0)))


def noise_level(demos) -> float:
    """Noise sigma of the positions: the third differences of a smooth curve sampled finely are
    ~0, of white noise N(0, sigma^2) have variance 20 sigma^2; sigma = 1.4826 MAD(third
    differences, all coordinates and demonstrations) / sqrt(20) (robust to the motion's own)."""
    d3 = np.concatenate([np.diff(d.pos, 3, axis=0).ravel() for d in demos])
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))


def typical_step(demos) -> float:
    """Median distance between consecutive samples over all demonstrations (data units)."""
    return float(np.median(np.concatenate([np.linalg.norm(np.diff(d.pos, axis=0), axis=1) for d in demos])))


def smoothing_window(demos) -> int | None:
    """The "auto" Savitzky-Golay window (module docstring, step 3), or None (data smooth)."""
    from scipy.signal import savgol_coeffs   # scipy.signal is slow to import; only here
    ratio = noise_level(demos) / max(typical_step(demos), np.finfo(float).tiny)
    if ratio <= SMOOTH_OFF_RATIO:
        return None
    longest = max(MIN_WINDOW, (min(len(d.t) for d in demos) // 4) // 2 * 2 + 1)
    for w in range(MIN_WINDOW, longest + 1, 2):
        if ratio * np.linalg.norm(savgol_coeffs(w, SG_ORDER, deriv=1)) <= VEL_NOISE:
            return w
    return longest


def resample_uniform(demo: Demonstration) -> Demonstration:
    """``demo`` on a uniform grid with its median step if a step deviates from it by more than
    IRREGULAR_TOL (velocities re-estimated), else ``demo`` itself. The grid's memory (its points x
    (1 + n) numbers x GRID_BYTES_PER_VALUE) is checked against ``max_bytes`` (:mod:`sosdyn.limits`)
    before it is allocated: a gap in the recording (steps of 1 us, then one of 500 s) would make
    it 5e8 points long."""
    steps = np.diff(demo.t)
    h = float(np.median(steps))
    if np.all(np.abs(steps - h) <= IRREGULAR_TOL * h):
        return demo
    points = np.floor((demo.t[-1] - demo.t[0]) / h + 1e-9) + 1          # a float: no int overflow
    check_bytes(points * (1 + demo.pos.shape[1]) * GRID_BYTES_PER_VALUE,
                f"resampling {demo.source or 'a demonstration'} to uniform time steps ({points:.3g} points of the "
                f"median step {h:.3g} s over {demo.duration:.4g} s; its steps range from {steps.min():.3g} to "
                f"{steps.max():.3g} s)",
                "if the long step is a gap in the recording (a pause, a clock jump), split the recording there "
                "or drop the isolated samples")
    t = demo.t[0] + h * np.arange(int(points))
    t[-1] = demo.t[-1] if t[-1] < demo.t[-1] - 0.5 * h else t[-1]
    pos = np.column_stack([np.interp(t, demo.t, demo.pos[:, i]) for i in range(demo.pos.shape[1])])
    return Demonstration.from_positions(t, pos, demo.source)


def rest_bounds(pos: np.ndarray, tol: float) -> tuple[int, int]:
    """(first, last) kept sample indices after trimming rest (module docstring, step 2)."""
    moved = np.flatnonzero(np.linalg.norm(pos - pos[0], axis=1) > tol)
    first = max(int(moved[0]) - 1, 0) if moved.size else 0
    away = np.flatnonzero(np.linalg.norm(pos - pos[-1], axis=1) > tol)
    last = int(away[-1]) + 1 if away.size else len(pos) - 1
    return first, max(last, first + 1)


def savgol_derivatives(t: np.ndarray, pos: np.ndarray, window: int, order: int = 1) -> list[np.ndarray]:
    """[pos, d pos/dt, ..., d^order pos/dt^order] of the uniformly sampled curve ``pos`` (T, n) at
    times ``t``, all from one cubic Savitzky-Golay fit over ``window`` samples (odd, >= 5;
    shortened to the curve's length); ``order`` <= 2 (the second derivative of the local cubic is
    exact for cubic motions)."""
    from scipy.signal import savgol_filter   # scipy.signal is slow to import; only here
    w = min(window, len(t) if len(t) % 2 else len(t) - 1)
    h = float(np.mean(np.diff(t)))
    return [savgol_filter(pos, w, SG_ORDER, deriv=d, delta=h, axis=0, mode="interp") for d in range(order + 1)]


def smooth(demo: Demonstration, window: int) -> Demonstration:
    """Positions and velocities of a uniformly sampled ``demo`` from a cubic Savitzky-Golay fit
    over ``window`` samples (odd, >= 5; shortened to the demo's length): :func:`savgol_derivatives`."""
    return Demonstration(demo.t, *savgol_derivatives(demo.t, demo.pos, window), demo.source)


def blend_shift(t: np.ndarray, shift: np.ndarray, fraction: float = BLEND_FRACTION) -> tuple[np.ndarray, np.ndarray]:
    """Displacement ``w(t) shift`` and its time derivative, (T, n) each: w = 3s^2 - 2s^3 with
    s = clip((t - t_b) / (t_T - t_b), 0, 1), t_b = t_T - fraction (t_T - t_0)."""
    span = fraction * (t[-1] - t[0])
    s = np.clip((t - (t[-1] - span)) / span, 0.0, 1.0)
    w, dw = 3 * s**2 - 2 * s**3, np.where((s > 0) & (s < 1), 6 * s * (1 - s) / span, 0.0)
    return w[:, None] * shift, dw[:, None] * shift


@dataclass(frozen=True)
class PreprocessReport:
    """What :func:`preprocess` did: noise sigma and typical step (data units), smoothing window
    (None = off), indices of resampled demos, samples trimmed at (start, end) per demo, the
    goal and each demo's end shift (data units, 0 when not aligned)."""

    noise: float
    step: float
    window: int | None
    resampled: list[int] = field(default_factory=list)
    trimmed: list[tuple[int, int]] = field(default_factory=list)
    goal: np.ndarray | None = None
    shifts: np.ndarray | None = None

    def lines(self, units: str = "") -> list[str]:
        """Human-readable summary, one line per step."""
        u = f" {units}" if units else ""
        out = [f"noise {self.noise:.3g}{u} ({self.noise / max(self.step, 1e-300):.2%} of a step); smoothing: "
               + (f"Savitzky-Golay, {self.window} samples" if self.window else "off (data smooth)")]
        if self.resampled:
            out.append(f"resampled to uniform time steps: demos {self.resampled}")
        cut = np.array(self.trimmed).reshape(-1, 2)
        if cut.any():
            out.append(f"trimmed rest in {int(np.count_nonzero(cut.any(axis=1)))} of {len(cut)} demos: up to "
                       f"{cut[:, 0].max()} samples at the start, {cut[:, 1].max()} at the end")
        if self.shifts is not None and np.any(self.shifts > 0):
            worst = int(np.argmax(self.shifts))
            out.append(f"ends aligned to the mean end: moved by median {np.median(self.shifts):.3g}{u}, max "
                       f"{self.shifts[worst]:.3g}{u} (demo {worst})")
        return out


def align_ends(demos, max_shift: float | None = None, fraction: float = BLEND_FRACTION):
    """Each demo blended onto the mean end g (module docstring, step 4): (Demonstrations, shifts).

    DemonstrationError when an end is farther than ``max_shift`` (default ALIGN_MAX x the
    bounding-box diagonal) from g, naming the value that would accept it."""
    goal, shifts = end_distances(demos)
    limit = ALIGN_MAX * _diagonal(demos) if max_shift is None else float(max_shift)
    worst = int(np.argmax(shifts))
    if shifts[worst] > limit:
        where = f"demo {worst} of {getattr(demos, 'name', '') or 'the set'}"
        units = getattr(demos, "units", "") or "units"
        raise DemonstrationError(f"{where} ends {shifts[worst]:.4g} {units} from the mean end point, more than "
                                 f"max_shift = {limit:.4g} ({ALIGN_MAX:.0%} of the data's diagonal by default): "
                                 f"its end is too far away to be one task. Try: drop that demo, or max_shift="
                                 f"{1.1 * shifts[worst]:.3g} (sosdyn fit --align-ends MAX) if they are one task.")
    out = []
    for d in demos:
        dx, dv = blend_shift(d.t, goal - d.pos[-1], fraction)
        out.append(Demonstration(d.t, d.pos + dx, d.vel + dv, d.source))
    return Demonstrations(out, getattr(demos, "name", ""), getattr(demos, "units", ""),
                          getattr(demos, "goal_tol", None), getattr(demos, "columns", None)), shifts


def check_options(smooth_window, align) -> None:
    """InputError unless ``smooth_window`` is "auto", "off", None or an odd int >= MIN_WINDOW and ``align``
    is "auto", True or False (:func:`preprocess`'s options, and the pose preprocessing's)."""
    if not (smooth_window in ("auto", "off", None) or (isinstance(smooth_window, (int, np.integer))
                                                        and not isinstance(smooth_window, bool)
                                                        and smooth_window >= MIN_WINDOW and smooth_window % 2)):
        raise InputError(f"smooth_window must be 'auto', 'off', None or an odd integer >= {MIN_WINDOW}, got "
                         f"{smooth_window!r}. Try: 'auto'.")
    if align not in ("auto", True, False):
        raise InputError(f"align must be 'auto', True or False, got {align!r}.")


def preprocess(demos, *, smooth_window: int | str | None = "auto", trim_rest: bool = True,
               align: bool | str = "auto", max_shift: float | None = None):
    """Steps 1-4 of the module docstring on ``demos``: (Demonstrations, PreprocessReport).

    ``smooth_window``: "auto" (from the noise), None or "off", or an odd int >= 5;
    ``trim_rest``: bool; ``align``: "auto" (when the ends spread more than ALIGN_MIN of the
    diagonal), True or False; ``max_shift``: the refusal distance of :func:`align_ends`.
    On LASA the defaults change nothing (uniform times, noise 1e-4 of a step, ends identical).
    """
    items = list(demos)
    if not items or any(not isinstance(d, Demonstration) or len(d.t) < MIN_WINDOW for d in items):
        raise InputError(f"preprocess needs Demonstrations of at least {MIN_WINDOW} samples each.")
    check_options(smooth_window, align)
    name, units = getattr(demos, "name", ""), getattr(demos, "units", "")
    resampled = [resample_uniform(d) for d in items]
    changed = [i for i, (a, b) in enumerate(zip(items, resampled)) if a is not b]
    sigma, step = noise_level(resampled), typical_step(resampled)
    trimmed, kept = [], []
    for d in resampled:
        a, b = rest_bounds(d.pos, REST_NOISE * sigma) if trim_rest else (0, len(d.t) - 1)
        trimmed.append((a, len(d.t) - 1 - b))
        kept.append(d if (a, b) == (0, len(d.t) - 1) else Demonstration(d.t[a:b + 1], d.pos[a:b + 1],
                                                                          d.vel[a:b + 1], d.source))
    short = [i for i, d in enumerate(kept) if len(d.t) < MIN_SAMPLES]
    if short:
        i = short[0]
        raise DemonstrationError(
            f"demo {i} ({resampled[i].source or name or 'the set'}) keeps {len(kept[i].t)} of its {len(resampled[i].t)} "
            f"samples once the rest at its ends is trimmed (rest: within {REST_NOISE:g} noise sigmas = "
            f"{REST_NOISE * sigma:.3g} of its first / last sample), fewer than the {MIN_SAMPLES} a demonstration "
            "needs: it barely moves, or jumps between two rests within a few samples. Try: drop that demo, "
            "record the motion at a higher rate, or keep the rest (trim_rest=False; sosdyn fit --trim-rest off).")
    window = smoothing_window(kept) if smooth_window == "auto" else (
        None if smooth_window in ("off", None) else int(smooth_window))
    out = Demonstrations([smooth(d, window) if window else d for d in kept], name, units,
                         getattr(demos, "goal_tol", None),      # the tolerance the set was accepted with
                         getattr(demos, "columns", None))
    goal, spread = end_distances(out)
    shifts = np.zeros(len(out))
    if align is True or (align == "auto" and spread.max() > ALIGN_MIN * _diagonal(out)):
        out, shifts = align_ends(out, max_shift)
    return out, PreprocessReport(sigma, step, window, changed, trimmed, goal, shifts)

"""Preprocessing of pose demonstrations: the steps of :mod:`.preprocess`, on both parts of the pose.

:func:`preprocess_poses` runs, on :class:`~.pose.PoseDemonstrations` (training demonstrations only,
so no test data leaks in):

1. **resample** irregular time stamps (:func:`~.preprocess.resample_uniform`'s rule and grid):
   positions by linear interpolation, orientations by spherical linear interpolation (slerp,
   :class:`scipy.spatial.transform.Slerp`: the geodesic between neighbouring samples).
2. **trim rest**: a sample rests while neither part has moved: the kept range is the union of
   :func:`~.preprocess.rest_bounds` of the positions (radius REST_NOISE x their noise sigma) and of the
   rotation vectors r = log(R_g^T R) (radius REST_NOISE x their noise sigma), R_g the chordal mean of
   the end orientations: a pure rotation in place is kept, a pause is not.
3. **smooth** (cubic Savitzky-Golay, ``"auto"``: :func:`~.preprocess.smoothing_window` of each part,
   the larger window for both): positions as :func:`~.preprocess.smooth`; orientations on the sphere in
   the log chart at R_g, R(t) = R_g exp(SG[r](t)), smooth wherever the demonstration stays away from
   the cut locus (it must stay within 170 deg of R_g: :func:`~.pose.demo_chart`).
4. **align ends**: positions by :func:`~.preprocess.align_ends` (``"auto"``: when the ends spread more
   than ALIGN_MIN of the diagonal; ``max_shift`` refuses), orientations by
   :func:`~.pose.align_orientations` onto R_g (``goal_tol_deg`` refuses; None leaves them to
   :meth:`~sosdyn.lfd.model.pose.PoseCDSP.fit`, which aligns them within its own tolerance), both with the
   same smoothstep over the last half of each demonstration.

Every demonstration keeps at least :data:`~.preprocess.MIN_WINDOW` samples; one that would not (a rest,
a jump, a rest) is refused with a hint (DemonstrationError). :class:`PosePreprocessReport` says what
each step did.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from sosdyn.errors import DemonstrationError, InputError
from .demonstrations import Demonstration, Demonstrations, end_distances
from .pose import (GOAL_TOL_DEG, PoseDemonstration, PoseDemonstrations, align_orientations, demo_chart,
                    from_chart, goal_orientation)
from .preprocess import (ALIGN_MIN, MIN_WINDOW, REST_NOISE, PreprocessReport, align_ends, check_options,
                         noise_level, resample_uniform, rest_bounds, savgol_derivatives, smoothing_window,
                         typical_step)


@dataclass(frozen=True)
class PosePreprocessReport:
    """What :func:`preprocess_poses` did: the position part as a
    :class:`~.preprocess.PreprocessReport` (noise, step, window, resampled, trimmed, goal, shifts) and the
    orientation part: its noise sigma and typical step (rad) and how far each end was turned (deg)."""

    position: PreprocessReport
    angle_noise: float
    angle_step: float
    turned_deg: tuple = ()

    def lines(self, units: str = "") -> list[str]:
        """Human-readable summary, one line per step (positions, then orientations)."""
        out = self.position.lines(units)
        out.insert(1, f"orientation noise {np.rad2deg(self.angle_noise):.3g} deg "
                      f"({self.angle_noise / max(self.angle_step, 1e-300):.2%} of a step)")
        if any(a > 0 for a in self.turned_deg):
            out.append(f"end orientations turned onto their mean: median {np.median(self.turned_deg):.3g} deg, "
                       f"max {max(self.turned_deg):.3g} deg")
        return out


def resample_pose(demo: PoseDemonstration) -> PoseDemonstration:
    """``demo`` on :func:`~.preprocess.resample_uniform`'s grid (positions interpolated linearly,
    orientations by slerp) when its stamps are irregular, else ``demo`` itself."""
    grid = resample_uniform(Demonstration.from_positions(demo.t, demo.pos, demo.source))
    if np.array_equal(grid.t, demo.t):
        return demo
    quat = Slerp(demo.t, demo.rotations)(grid.t).as_quat(scalar_first=True)
    return PoseDemonstration(grid.t, grid.pos, quat if quat[0] @ demo.quat[0] >= 0 else -quat, demo.source)


def _parts(demos, goal_quat) -> tuple[list, list]:
    """Per demo, positions and rotation vectors as Demonstrations (for the noise and window rules)."""
    pos = [Demonstration.from_positions(d.t, d.pos, d.source) for d in demos]
    rot = [Demonstration.from_positions(d.t, demo_chart(d.quat, goal_quat, f"pose demo {d.source!r}"), d.source)
           for d in demos]
    return pos, rot


def rest_range(demo: PoseDemonstration, goal_quat, sigma: float, sigma_r: float) -> tuple[int, int]:
    """(first, last) kept sample of ``demo`` after trimming its rest (module docstring, step 2): the union
    of :func:`~.preprocess.rest_bounds` of the parts that move (the position beyond REST_NOISE ``sigma``
    data units, the rotation vector beyond REST_NOISE ``sigma_r`` rad); everything if neither moves."""
    bounds = []
    for part, tol in ((demo.pos, REST_NOISE * sigma),
                      (demo_chart(demo.quat, goal_quat, f"pose demo {demo.source!r}"), REST_NOISE * sigma_r)):
        if np.any(np.linalg.norm(part - part[0], axis=1) > tol):
            bounds.append(rest_bounds(part, tol))
    if not bounds:
        return 0, len(demo.t) - 1
    return min(a for a, _ in bounds), max(b for _, b in bounds)


def _check_length(demo, label: str) -> None:
    if len(demo.t) < MIN_WINDOW:
        raise DemonstrationError(f"pose demo {label!r} keeps {len(demo.t)} samples after trimming its rest "
                                 f"(fewer than {MIN_WINDOW}): it rests, jumps and rests. Try: trim_rest=False "
                                 "(sosdyn fit --trim-rest off), or drop that demonstration.")


def preprocess_poses(demos: PoseDemonstrations, *, smooth_window: int | str | None = "auto", trim_rest: bool = True,
                     align: bool | str = "auto", max_shift: float | None = None,
                     goal_tol_deg: float | None = GOAL_TOL_DEG) -> tuple[PoseDemonstrations, PosePreprocessReport]:
    """Steps 1-4 of the module docstring: (PoseDemonstrations, PosePreprocessReport). The options
    are :func:`~.preprocess.preprocess`'s, and ``goal_tol_deg`` bounds the end orientations (None: they
    are not aligned here)."""
    if not isinstance(demos, PoseDemonstrations):
        raise InputError(f"preprocess_poses takes PoseDemonstrations, got {type(demos).__name__}. "
                         "Try: sosdyn.preprocess for position demonstrations.")
    check_options(smooth_window, align)
    for d in demos:
        _check_length(d, d.source)
    items = [resample_pose(d) for d in demos]
    changed = [i for i, (a, b) in enumerate(zip(demos, items)) if a is not b]
    goal_quat = goal_orientation(PoseDemonstrations(items))
    pos, rot = _parts(items, goal_quat)
    sigma, step, sigma_r, step_r = noise_level(pos), typical_step(pos), noise_level(rot), typical_step(rot)
    trimmed, kept = [], []
    for d in items:
        a, b = rest_range(d, goal_quat, sigma, sigma_r) if trim_rest else (0, len(d.t) - 1)
        trimmed.append((a, len(d.t) - 1 - b))
        kept.append(d if (a, b) == (0, len(d.t) - 1) else PoseDemonstration(d.t[a:b + 1], d.pos[a:b + 1],
                                                                            d.quat[a:b + 1], d.source))
        _check_length(kept[-1], d.source)
    pos, rot = _parts(kept, goal_quat)
    if smooth_window == "auto":
        windows = [w for w in (smoothing_window(pos), smoothing_window(rot)) if w is not None]
        window = max(windows) if windows else None
    else:
        window = None if smooth_window in ("off", None) else int(smooth_window)
    if window:
        kept = [PoseDemonstration(d.t, savgol_derivatives(d.t, d.pos, window, 0)[0],
                                  from_chart(savgol_derivatives(d.t, r.pos, window, 0)[0], goal_quat), d.source)
                for d, r in zip(kept, rot)]
    out = PoseDemonstrations(kept, demos.name, demos.units, demos.notes)
    positions = Demonstrations([Demonstration.from_positions(d.t, d.pos, d.source) for d in out])
    goal, spread = end_distances(positions)
    shifts, turned = np.zeros(len(out)), [0.0] * len(out)
    X = np.vstack([d.pos for d in out])
    if align is True or (align == "auto" and spread.max() > ALIGN_MIN * np.linalg.norm(np.ptp(X, axis=0))):
        aligned, shifts = align_ends(positions, max_shift)
        out = PoseDemonstrations([PoseDemonstration(d.t, a.pos, d.quat, d.source) for d, a in zip(out, aligned)],
                                 out.name, out.units, out.notes)
    if align is not False and goal_tol_deg is not None:
        out, turned = align_orientations(out, goal_orientation(out), goal_tol_deg)
    report = PreprocessReport(sigma, step, window, changed, trimmed, goal, shifts)
    return out, PosePreprocessReport(report, sigma_r, step_r, tuple(float(a) for a in turned))

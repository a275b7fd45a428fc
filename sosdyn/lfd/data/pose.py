"""Pose demonstrations: position x (T, 3) and orientation q (T, 4, unit quaternion, w x y z).

A file is a pose file (:func:`is_pose_file`) when its header names any of qw, qx, qy, qz; then
:func:`sosdyn.load_demos` and ``sosdyn fit`` read it here (unless position columns are selected).
Reading (:func:`pose_columns`, :func:`read_pose_csv`): the header decides the quaternion's order,
``qw,qx,qy,qz`` (scalar first) or ``qx,qy,qz,qw`` (scalar last) by the column names; a header whose
quaternion columns are not four distinct names among qw/qx/qy/qz is refused with a hint. The time
column and its units follow the position files' rules (:mod:`.columns`: t, time, timestamp, t_ms, ...;
times from the first stamp, in s; an implausibly long demonstration refused). Each row's norm is checked (refused outside [1 - NORM_REFUSE, 1 +
NORM_REFUSE]: not a rotation) and the row divided by it (the largest deviation is reported).

Sign continuity (:func:`sign_continuous`): q and -q are one rotation; each sample is flipped to
the one of +-q_k nearer (larger dot product) to the previous, kept, sample.

The goal orientation (:func:`goal_orientation`) is the chordal L2 mean of the end orientations
(:meth:`scipy.spatial.transform.Rotation.mean`: the rotation R minimising sum_i ||R - R_i||_F^2).
Scattered ends (:func:`align_orientations`), like scattered end positions: each demo i is turned
by R_i(t) <- R_i(t) exp(w(t) log(R_i(T)^T R_g)), w(t) the smoothstep of the position alignment
(:func:`~.preprocess.blend_shift`: 0 before the last half of the demo, rising to 1 at its end), so it
starts where it started and ends at R_g; the angle moved is reported; ends more than
``goal_tol_deg`` from R_g are refused with the value to try.

The chart (:func:`chart`, :func:`from_chart`): r = log(R_g^T R), the rotation vector of the rotation
from the goal, |r| in [0, pi] its geodesic angle from the goal (at the cut locus |r| = pi the two
logarithms +-pi u are both valid; scipy picks one). Demonstrations must stay below pi - CHART_MARGIN
from their goal (:func:`demo_chart`: a demo crossing the cut locus would jump in r); starts and run-time
states may be anywhere (docs/theory.md, "Poses"). Geodesic angles between quaternions:
:func:`angle_matrix`; the demos split into positions and rotation vectors: :func:`split_demonstrations`.
All quaternion algebra is scipy's :class:`~scipy.spatial.transform.Rotation` (scalar_first=True for w x y z).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.errors import DemonstrationError, InputError
from .columns import TIME_UNITS, check_duration, check_time_units, time_header_names, time_unit
from .demonstrations import Demonstration, Demonstrations, merge_repeated_stamps, time_problem
from .preprocess import blend_shift

POSITION_COLUMNS = ("x", "y", "z")
SCALAR_FIRST, SCALAR_LAST = ("qw", "qx", "qy", "qz"), ("qx", "qy", "qz", "qw")
NORM_REPORT = 1e-6            # row norms further than this from 1 are reported after renormalising
NORM_REFUSE = 0.1             # ... and further than this are refused (not a unit quaternion)
CHART_MARGIN = np.deg2rad(10.0)     # demonstrations stay below pi - CHART_MARGIN from their goal
GOAL_TOL_DEG = 20.0           # default refusal of end orientations scattered more than this


@dataclass(frozen=True, eq=False)
class PoseDemonstration:
    """One pose demonstration: ``t`` (T,) s, ``pos`` (T, 3), ``quat`` (T, 4) unit, w x y z."""

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    source: str = ""

    def __post_init__(self):
        t, pos, quat = (np.array(getattr(self, f), dtype=float) for f in ("t", "pos", "quat"))
        if t.ndim != 1 or pos.shape != (len(t), 3) or quat.shape != (len(t), 4):
            raise DemonstrationError(f"pose demo {self.source!r}: shapes t {t.shape}, pos {pos.shape}, quat "
                                     f"{quat.shape}; expected (T,), (T, 3), (T, 4) (quaternions w x y z).")
        if not (np.isfinite(pos).all() and np.isfinite(quat).all()):
            raise DemonstrationError(f"pose demo {self.source!r}: NaN or inf in pos or quat; remove those rows.")
        problem = time_problem(t)
        if problem:
            raise DemonstrationError(f"pose demo {self.source!r}: {problem}.")
        for name, arr in (("t", t), ("pos", pos), ("quat", unit_quaternions(quat, self.source)[0])):
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @property
    def rotations(self) -> Rotation:
        return Rotation.from_quat(self.quat, scalar_first=True)

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` in seconds."""
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True)
class PoseDemonstrations:
    """Pose demonstrations sharing a ``name`` and position ``units``; ``notes``: what reading did."""

    demos: tuple
    name: str = ""
    units: str = ""
    notes: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "demos", tuple(self.demos))
        if not self.demos or not all(isinstance(d, PoseDemonstration) for d in self.demos):
            raise InputError("PoseDemonstrations needs at least one PoseDemonstration; build them with "
                             "PoseDemonstration(t, pos, quat) or read_pose_csv(path).")

    def __len__(self):
        return len(self.demos)

    def __getitem__(self, i):
        return PoseDemonstrations(self.demos[i], self.name, self.units, self.notes) if isinstance(i, slice) \
            else self.demos[i]

    def __iter__(self):
        return iter(self.demos)

    @property
    def goal_pos(self) -> np.ndarray:
        return np.mean([d.pos[-1] for d in self.demos], axis=0)


def unit_quaternions(quat, label: str = "") -> tuple[np.ndarray, float]:
    """Rows of ``quat`` (T, 4) divided by their norms, and the largest | |q| - 1 |; refused if that
    exceeds NORM_REFUSE (the columns are not a unit quaternion)."""
    quat = np.asarray(quat, dtype=float)
    norms = np.linalg.norm(quat, axis=1)
    dev = np.abs(norms - 1.0)
    worst = int(np.argmax(dev)) if len(dev) else 0
    if len(dev) and dev[worst] > NORM_REFUSE:
        raise DemonstrationError(
            f"{label or 'pose data'}: quaternion row {worst} has norm {norms[worst]:.4g}, not 1 (tolerance "
            f"{NORM_REFUSE}). Try: check the column order and that these four columns are a unit quaternion.")
    return quat / norms[:, None], float(dev.max(initial=0.0))


def sign_continuous(quat) -> tuple[np.ndarray, int]:
    """q_k flipped to the one of +-q_k nearer the previous (kept) sample; and how many were flipped."""
    quat = np.asarray(quat, dtype=float)
    flips = np.concatenate([[1.0], np.where(np.einsum("ti,ti->t", quat[1:], quat[:-1]) < 0, -1.0, 1.0)])
    signs = np.cumprod(flips)
    return quat * signs[:, None], int(np.count_nonzero(signs < 0))


def pose_columns(header) -> tuple[list[int], list[int], int | None, str]:
    """Indices of (x, y, z), of the quaternion as (w, x, y, z), of the time column (or None), and the
    order read ("scalar first" / "scalar last"), from the CSV ``header`` names (case-insensitive)."""
    names = [h.strip().lower() for h in header]
    hint = ("Try: a header t,x,y,z,qw,qx,qy,qz (scalar first) or t,x,y,z,qx,qy,qz,qw (scalar last).")
    if len(set(names)) != len(names):
        raise InputError(f"pose CSV header {header} repeats a column name. {hint}")
    missing = [c for c in POSITION_COLUMNS + SCALAR_FIRST if c not in names]
    if missing:
        raise InputError(f"pose CSV header {header} lacks {missing}: the quaternion order cannot be told "
                         f"from unnamed columns. {hint}")
    q = [names.index(c) for c in SCALAR_FIRST]
    order = [c for c in names if c in SCALAR_FIRST]
    if order not in (list(SCALAR_FIRST), list(SCALAR_LAST)):
        raise InputError(f"pose CSV header {header}: quaternion columns in the order {order}, neither w x y z "
                         f"nor x y z w; refusing to guess. {hint}")
    time = next((names.index(c) for c in time_header_names() if c in names), None)
    return [names.index(c) for c in POSITION_COLUMNS], q, time, \
        "scalar first" if order == list(SCALAR_FIRST) else "scalar last"


def _csv_rows(path: Path) -> list[list[str]]:
    try:
        with path.open(newline="") as fh:
            return list(csv.reader(fh))
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}.") from exc


def is_pose_file(path) -> bool:
    """Does the CSV at ``path`` have a header naming a quaternion column (qw, qx, qy or qz, any case)?"""
    path = Path(path)
    if path.suffix.lower() != ".csv" or not path.is_file():
        return False
    try:
        with path.open(newline="") as fh:
            header = next(csv.reader(fh), [])
    except (OSError, UnicodeDecodeError):
        return False                 # the position loader reports it
    return any(h.strip().lower() in SCALAR_FIRST for h in header)


def read_pose_csv(path, dt: float | None = None, time_units: str | None = None) -> tuple[PoseDemonstration, list[str]]:
    """One pose demonstration from a CSV with a header (:func:`pose_columns`); without a time column
    the samples are ``dt`` s apart; samples sharing a time stamp become one (positions: their mean;
    quaternions, made sign-continuous first: their normalised mean, the chordal mean of nearby rotations),
    as :func:`~.demonstrations.merge_repeated_stamps` does for position files. Returns it and notes (order
    read, renormalisation, flips, merged stamps)."""
    path = Path(path)
    rows = _csv_rows(path)
    if len(rows) < 2:
        raise DemonstrationError(f"{path}: no data rows under the header.")
    pos_i, q_i, t_i, order = pose_columns(rows[0])
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=float)
    except ValueError as exc:
        raise DemonstrationError(f"{path}: a value is not a number ({exc}).") from exc
    if (t_i is None) == (dt is None):
        raise InputError(f"{path}: {'no' if t_i is None else 'both dt and a'} time column. Try: "
                         + ("dt= (seconds between samples; --dt in sosdyn fit)." if t_i is None else "drop dt."))
    if t_i is None:
        t = dt * np.arange(len(data))
    else:
        column = rows[0][t_i].strip().lower()
        unit = time_unit(column, check_time_units(time_units), str(path))
        t = (data[:, t_i] - data[0, t_i]) * TIME_UNITS[unit]
        check_duration(t, unit, str(path), f"time column {column!r}")
    quat, dev = unit_quaternions(data[:, q_i], str(path))
    quat, flips = sign_continuous(quat)
    t, merged, dropped, averaged = merge_repeated_stamps(t, np.column_stack([data[:, pos_i], quat]))
    pos, quat = merged[:, :len(pos_i)], merged[:, len(pos_i):]
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)      # a stamp's mean quaternion (sign-continuous rows)
    notes = [f"{path.name}: quaternion read {order} (w x y z from columns {[rows[0][i] for i in q_i]})"]
    if dropped or averaged:
        notes.append(f"{path.name}: repeated time stamps: one sample per stamp kept, {dropped} identical row(s) "
                     f"dropped and {averaged} differing row(s) averaged into their stamp's sample (quaternions: "
                     "their normalised mean)")
    if dev > NORM_REPORT:
        notes.append(f"{path.name}: quaternions renormalised (largest | |q| - 1 | = {dev:.2e})")
    if flips:
        notes.append(f"{path.name}: {flips} samples sign-flipped for continuity (q and -q are one rotation)")
    return PoseDemonstration(t, pos, quat, str(path)), notes


def load_pose_demos(paths, units: str = "", name: str = "", dt: float | None = None,
                    time_units: str | None = None) -> PoseDemonstrations:
    """Pose demonstrations from CSV files (:func:`read_pose_csv`), notes collected."""
    paths = [paths] if isinstance(paths, (str, Path)) else list(paths)
    demos, notes = [], []
    for p in paths:
        d, n = read_pose_csv(p, dt, time_units)
        demos.append(d)
        notes += n
    return PoseDemonstrations(demos, name or (Path(paths[0]).parent.name if paths else ""), units, tuple(notes))


def goal_orientation(demos: PoseDemonstrations) -> np.ndarray:
    """The chordal mean of the demos' end orientations, as a unit quaternion (w x y z)."""
    ends = Rotation.from_quat([d.quat[-1] for d in demos], scalar_first=True)
    return ends.mean().as_quat(scalar_first=True)


def align_orientations(demos: PoseDemonstrations, goal_quat, goal_tol_deg: float = GOAL_TOL_DEG):
    """Demos turned so each ends at ``goal_quat`` (module docstring), and each demo's end angle moved
    (degrees); refused (DemonstrationError with the value to try) beyond ``goal_tol_deg``."""
    Rg = Rotation.from_quat(goal_quat, scalar_first=True)
    out, moved = [], []
    for i, d in enumerate(demos):
        fix = (d.rotations[-1].inv() * Rg).as_rotvec()
        angle = float(np.rad2deg(np.linalg.norm(fix)))
        if angle > goal_tol_deg:
            raise DemonstrationError(
                f"pose demo {i} ({d.source}) ends {angle:.3g} deg from the mean end orientation, more than "
                f"goal_tol_deg = {goal_tol_deg:g}; the demos do not share a goal orientation. Try: drop that "
                f"demo, or goal_tol_deg={1.1 * angle:.3g}.")
        w, _ = blend_shift(d.t, np.ones(1))
        turned = d.rotations * Rotation.from_rotvec(w * fix)
        quat, _ = sign_continuous(turned.as_quat(scalar_first=True))
        quat = quat if quat[0] @ d.quat[0] >= 0 else -quat
        out.append(PoseDemonstration(d.t, d.pos, quat, d.source))
        moved.append(angle)
    return PoseDemonstrations(out, demos.name, demos.units, demos.notes), moved


def chart(quat, goal_quat) -> np.ndarray:
    """r = log(R_g^T R) (rotation vectors, radians, |r| <= pi) of the rows of ``quat`` (w x y z)."""
    Rg = Rotation.from_quat(goal_quat, scalar_first=True)
    return (Rg.inv() * Rotation.from_quat(np.atleast_2d(quat), scalar_first=True)).as_rotvec()


def from_chart(r, goal_quat) -> np.ndarray:
    """Unit quaternions (w x y z) R_g exp(r) of the rotation vectors r (m, 3)."""
    Rg = Rotation.from_quat(goal_quat, scalar_first=True)
    return (Rg * Rotation.from_rotvec(np.atleast_2d(r))).as_quat(scalar_first=True)


def demo_chart(quat, goal_quat, label: str = "orientation") -> np.ndarray:
    """:func:`chart` of a demonstration's samples; refused if any angle |r| >= pi - CHART_MARGIN (a
    demonstration near the cut locus may jump between the two logarithms)."""
    r = chart(quat, goal_quat)
    angle = np.linalg.norm(r, axis=1)
    worst = int(np.argmax(angle))
    if angle[worst] >= np.pi - CHART_MARGIN:
        raise DemonstrationError(
            f"{label} row {worst} is {np.rad2deg(angle[worst]):.1f} deg from the goal orientation, beyond "
            f"{np.rad2deg(np.pi - CHART_MARGIN):.0f} deg: near the half turn the rotation vector from the goal "
            "jumps. Try: demonstrations that end within a half turn less 10 deg of where they turned from.")
    return r


def angle_matrix(qa, qb) -> np.ndarray:
    """(N, M) geodesic angles in degrees: theta = 2 arccos |<a_i, b_j>| (the rotation of R_a^T R_b)."""
    dots = np.clip(np.abs(np.asarray(qa, float) @ np.asarray(qb, float).T), 0.0, 1.0)
    return np.rad2deg(2.0 * np.arccos(dots))


def split_demonstrations(demos: PoseDemonstrations, goal_quat) -> tuple[Demonstrations, Demonstrations]:
    """(positions, rotation vectors): the demos' positions x and their r = :func:`demo_chart` at
    ``goal_quat``, each as :class:`Demonstrations` (velocities estimated from the samples)."""
    pos = Demonstrations([Demonstration.from_positions(d.t, d.pos, d.source) for d in demos], demos.name,
                         demos.units)
    rot = Demonstrations([Demonstration.from_positions(d.t, demo_chart(d.quat, goal_quat, f"pose demo {d.source!r}"),
                                                       d.source) for d in demos], demos.name, "rad")
    return pos, rot

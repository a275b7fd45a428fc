"""PoseCDSP: a certified model of position and orientation as two certified blocks (docs/theory.md, "Poses");
the pose family of the model interface (:class:`~.base.MotionModel`).

The pose (x, R) is carried by the chart state s = (x, r), r = log(R_g^T R) the rotation vector of the
orientation from the goal orientation R_g (:func:`~sosdyn.lfd.data.pose.chart`). The model is

    xdot = F_x(x)        the certified CDSP of the positions (``position_``, as a position model),
    rdot = F_r(r)        a CDSP of r in the identity metric (``orientation_``, :mod:`~sosdyn.lfd.fit.pose`),

so the position never depends on the orientation: an orientation-only start or a turn of the goal
orientation moves the position by exactly 0. The orientation's certificate makes the geodesic angle
|r| = angle(R, R_g) decrease, d|r|^2/dt <= -gamma |r|^2, along every trajectory, so a state that starts
in the chart (|r| < pi, any orientation but the exact half turn, which has two logarithms and takes
either) never leaves it: every start converges, with no refusal. The orientation block's rate is
0.5 / T (T the demos' median duration) and it settles: a speed floor within goal_tol_deg of the goal, a
time change with factor >= 1 that keeps all of the above (:func:`~sosdyn.lfd.fit.pose.settle_floor`).
A block that does not move in the demonstrations is fitted as a still block
(:func:`~sosdyn.lfd.fit.pose.still_block`, ``still_``).

The predictor evaluates one pose in plain floats (:mod:`~sosdyn.lfd.runtime.pose`, the same formulas).

Rollout: the chart state is integrated (the CDSP's integrator, absolute tolerance relative to each
block's scale) and mapped by R = R_g exp(r): unit quaternions by construction. Velocities: v = xdot,
and the world angular velocity omega = R J_r(r) rdot (:func:`~sosdyn.lfd.runtime.pose.body_velocity`).
A goal pose (x_g', R_g') translates the position field and moves the chart: r' = log(R_g'^T R).

Speed limits (``max_speed`` on |v|, data units / s; ``max_angular_speed`` on |omega|, rad / s): the
chart velocity is scaled by one factor lambda, the speed limit's of the joint ratio of |v| / v_max and
|omega| / w_max (:func:`~sosdyn.lfd.runtime.pose.pose_speed_factor`, built on :mod:`~sosdyn.lfd.runtime.states`;
|v| < v_max, |omega| < w_max); one positive factor on the whole velocity keeps the paths and the goal (a time
change of the certified system).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.errors import InputError, ModelFileError, NotFittedError
from ..data.pose import (GOAL_TOL_DEG, PoseDemonstrations, align_orientations, chart, from_chart, goal_orientation,
                         split_demonstrations)
from ..data.pose_preprocess import preprocess_poses
from ..fit.floor import describe
from ..fit.params import preset_params
from ..fit.pose import (check_moves, check_settle_size, isotropic_demonstrations, orientation_params, settle_floor,
                        settles, still_block)
from ..rollout import ATOL_REL, rollout as integrate
from ..rollout.quality import HORIZON
from ..runtime.pose import (body_velocity_one, chart_one, check_limits, pose_speed_factor, pose_to_cpp, pose_to_python,
                            rotate_one)
from .base import Layout, MotionModel, Reproductions
from .cdsp import CDSP, DEFAULTS
from .content import BLOCKS, POSE_FORMAT, POSE_VERSION, pose_fields
from .pose_score import pose_reproduction_table
from .reach import metric_matrix, reach_box

#: The numbers of a pose (a start, a goal, a rollout row) and of a push (a world rotation vector w).
POSE_NAMES = ("x", "y", "z", "qw", "qx", "qy", "qz")
PUSH_NAMES = ("dx", "dy", "dz", "wx", "wy", "wz")


@dataclass
class PoseTrajectory:
    """A pose rollout: ``t`` (T,), ``pos`` (T, 3), ``quat`` (T, 4 unit, w x y z), ``goal_history`` (T, 7): the
    goal pose in effect at each sample."""

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    goal_history: np.ndarray | None = None

    @property
    def states(self) -> np.ndarray:
        """The rows (x, y, z, qw, qx, qy, qz), (T, 7)."""
        return np.hstack([self.pos, self.quat])


@dataclass(frozen=True)
class PoseCertificateReport:
    """The two blocks' certificate checks (:class:`~sosdyn.lfd.fit.certificate.CertificateReport` each)."""

    position: object
    orientation: object

    @property
    def passed(self) -> bool:
        return bool(self.position.passed and self.orientation.passed)

    def __str__(self) -> str:
        return f"position: {self.position}\norientation (identity metric: the angle never increases): {self.orientation}"


class PoseCDSP(MotionModel):
    """Learn a certified pose motion (position and orientation) from :class:`PoseDemonstrations`.

    ``goal_tol_deg``: end orientations further than this from their chordal mean are refused (nearer
    ones are aligned to it, ``orientation_moved_deg_``); every other keyword is a :class:`CDSP`
    parameter of the position block ``position_``, and of the orientation block ``orientation_`` with
    the identity metric and no warp (:func:`~sosdyn.lfd.fit.pose.orientation_params`).

    Learned: ``goal_quat_`` (w x y z), ``position_`` and ``orientation_`` (CDSPs; the orientation's goal
    is r = 0), ``still_`` ({"position": a or None, "orientation": a or None}: the rate of a block that did
    not move in the demonstrations), ``orientation_moved_deg_`` (set by ``fit``).
    """

    name = "PoseCDSP"
    file_format, file_version = POSE_FORMAT, POSE_VERSION
    columns_ = None             # pose files are read by their own header rule (x, y, z and a quaternion)

    def __init__(self, goal_tol_deg: float = GOAL_TOL_DEG, **cdsp_params):
        if isinstance(goal_tol_deg, bool) or not isinstance(goal_tol_deg, (int, float)) or \
                not 0 < goal_tol_deg < 180:
            raise InputError(f"goal_tol_deg must be a number in (0, 180), got {goal_tol_deg!r}.")
        self.goal_tol_deg = float(goal_tol_deg)
        unknown = sorted(set(cdsp_params) - set(DEFAULTS))
        if unknown:
            raise InputError(f"PoseCDSP: unknown parameters {unknown}. Try: goal_tol_deg or a CDSP parameter "
                             f"({', '.join(DEFAULTS)}).")
        self.progress = cdsp_params.pop("progress", None)     # as CDSP's: called with each history row
        self.cdsp_params = cdsp_params
        CDSP(**cdsp_params).check_params()

    def get_params(self) -> dict:
        return {"goal_tol_deg": self.goal_tol_deg, **CDSP(**self.cdsp_params).get_params()}

    @classmethod
    def preset(cls, name: str, **overrides) -> PoseCDSP:
        """An unfitted pose model whose blocks have the CDSP preset ``name``, then ``overrides``."""
        return cls(**{**preset_params(name), **overrides})

    @classmethod
    def prepare(cls, demos, smooth_window="auto", trim_rest=True, align="auto", max_shift=None):
        """(demos preprocessed, notes, []): :func:`~sosdyn.lfd.data.pose_preprocess.preprocess_poses` on both
        parts (the end orientations are left to :meth:`fit`, which aligns them within ``goal_tol_deg``), and
        what reading changed (renormalised quaternions, sign flips, merged time stamps)."""
        result, report = preprocess_poses(demos, smooth_window=smooth_window, trim_rest=trim_rest, align=align,
                                          max_shift=max_shift, goal_tol_deg=None)
        read = [f"read: {n}" for n in demos.notes if any(k in n for k in ("renormalised", "sign-flipped", "repeated"))]
        return result, read + [f"preprocess: {line}" for line in report.lines(demos.units)], []

    def __repr__(self) -> str:
        """``PoseCDSP(goal_tol_deg=20.0, ...)``: the parameters given; fitted, also the goal pose, each
        block's components and whether the certificates passed."""
        args = [f"goal_tol_deg={self.goal_tol_deg:g}"] + [f"{k}={v!r}" for k, v in self.cdsp_params.items()]
        if hasattr(self, "position_"):
            blocks = ", ".join(f"{b}: " + (f"still (rate {self.still_[b]:.3g}/s)" if self.still_[b] else
                                          f"K={getattr(self, b + '_').C_.shape[0]}") for b in BLOCKS)
            args.append(f"fitted: goal=({np.array2string(self.goal_pos_, precision=4, separator=', ')}, "
                        f"{np.array2string(self.goal_quat_, precision=4, separator=', ')}), {blocks}, "
                        f"certified={self.certified_}")
        return f"PoseCDSP({', '.join(args)})"

    def fit(self, demos: PoseDemonstrations) -> PoseCDSP:
        """Goal orientation, aligned end orientations, then the two certified blocks (module docstring)."""
        if not isinstance(demos, PoseDemonstrations):
            raise InputError(f"PoseCDSP.fit takes PoseDemonstrations (sosdyn.lfd.data.pose.load_pose_demos), "
                             f"got {type(demos).__name__}.")
        goal_quat = goal_orientation(demos)
        aligned, self.orientation_moved_deg_ = align_orientations(demos, goal_quat, self.goal_tol_deg)
        pos, rot = split_demonstrations(aligned, goal_quat)
        still = {"position": still_block(pos, "position"), "orientation": still_block(rot, "orientation")}
        check_moves(still["position"], still["orientation"], demos.name)
        duration = float(np.median([d.duration for d in demos]))
        params = {"position": self.cdsp_params, "orientation": orientation_params(self.cdsp_params, duration)}
        goals = {"position": pos.goal, "orientation": np.zeros(3)}
        settle = settles(self.cdsp_params)
        if settle and still["orientation"] is None:
            check_settle_size(rot)
        for block, data in (("position", pos), ("orientation", rot)):
            rate = still[block]
            if rate is not None:
                data = isotropic_demonstrations(3, rate, goals[block], data.units, data.name)
            model = CDSP(**{**params[block], **({"n_components": 1} if rate else {})},
                         progress=self.progress and tagged(self.progress, block)).fit(data)
            if rate is not None or block == "orientation":
                model.goal_ = goals[block]    # exactly (aligned ends, or symmetric synthetic ones: at round-off)
            if block == "orientation" and settle and rate is None:
                model.floor_, model.floor_arrivals_ = settle_floor(lambda R, m=model: m.field(R, m.goal_), data,
                                                                   np.deg2rad(self.goal_tol_deg))
            setattr(self, f"{block}_", model)
        self.goal_quat_, self.still_ = goal_quat, still
        return self

    # ------------------------------------------------------------------ state and chart
    def _check_fitted(self):
        if not hasattr(self, "position_"):
            raise NotFittedError("this PoseCDSP is not fitted yet; call fit(pose_demos) first")

    @property
    def cdsp_(self) -> CDSP:
        """The position block (``position_``)."""
        return self.position_

    @property
    def goal_pos_(self) -> np.ndarray:
        return self.position_.goal_

    @property
    def units_(self) -> str:
        return self.position_.units_

    @property
    def dt_(self) -> float:
        return self.position_.dt_

    @property
    def certified_(self) -> bool:
        return bool(self.position_.certified_ and self.orientation_.certified_)

    @property
    def verification_(self) -> PoseCertificateReport:
        return PoseCertificateReport(self.position_.verification_, self.orientation_.verification_)

    @property
    def history_(self) -> list:
        """Both blocks' convex steps (position, then orientation)."""
        return [*self.position_.history_, *self.orientation_.history_]

    def accept(self, report: PoseCertificateReport) -> None:
        """Record the check a loaded file passed, block by block."""
        self.position_.accept(report.position)
        self.orientation_.accept(report.orientation)

    def names(self) -> tuple[str, ...]:
        return POSE_NAMES[:3]

    def layout(self) -> Layout:
        return Layout(POSE_NAMES, (PUSH_NAMES,), POSE_NAMES, POSE_NAMES)

    @staticmethod
    def _pose(p, what: str) -> tuple[np.ndarray, np.ndarray]:
        """(x, unit q) of a pose p = (x, y, z, qw, qx, qy, qz); InputError if not 7 finite numbers with a
        quaternion of norm in (0.5, 1.5) (renormalised)."""
        try:
            p = np.asarray(p, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{what} must be 7 numbers (x, y, z, qw, qx, qy, qz), got {p!r:.60}.") from None
        if p.shape != (7,) or not np.isfinite(p).all():
            raise InputError(f"{what} must be 7 finite numbers (x, y, z, qw, qx, qy, qz), got shape {p.shape}"
                             f"{'' if p.shape != (7,) else ' with NaN or inf'}.")
        return p[:3], PoseCDSP._quat(p[3:], what)

    @staticmethod
    def _quat(q, what: str) -> np.ndarray:
        """q / |q| for a finite 4-vector with |q| in (0.5, 1.5); InputError otherwise (zero, NaN, inf, norm 100)."""
        try:
            q = np.asarray(q, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{what}: the quaternion must be 4 numbers (w, x, y, z), got {q!r:.60}.") from None
        norm = float(np.linalg.norm(q)) if q.shape == (4,) and np.isfinite(q).all() else np.nan
        if not 0.5 < norm < 1.5:
            raise InputError(f"{what}: the quaternion {q} is not a finite unit 4-vector (w, x, y, z)"
                             f"{f' (norm {norm:.3g})' if np.isfinite(norm) else ''}. Try: a unit quaternion, "
                             "e.g. 1,0,0,0 for the identity.")
        return q / norm

    def _goal(self, goal) -> tuple[np.ndarray, np.ndarray]:
        return (self.goal_pos_, self.goal_quat_) if goal is None else self._pose(goal, "goal")

    def field(self, S, goal_pos) -> np.ndarray:
        """The chart velocity (m, 6) at the chart states S = (x, r) (m, 6) for the goal position ``goal_pos``
        (the orientation's goal is r = 0 in the chart at the goal orientation)."""
        return np.hstack([self.position_.field(S[:, :3], goal_pos), self.orientation_.field(S[:, 3:], np.zeros(3))])

    # ------------------------------------------------------------------ motion
    def predictor(self, max_speed=None, max_angular_speed=None, goal=None, **other):
        """``step(x, quat, goal=None) -> (v, omega)``: linear velocity (3,) and world angular velocity
        (3,) at the position x and orientation quat (w x y z), for the goal pose (7-vector; default
        the model's, fixed here or per call); both scaled by one factor so that |v| <= max_speed and
        |omega| <= max_angular_speed (rad/s) when given. Every input is checked (InputError)."""
        self.refuse(other, "predictor")
        self._check_fitted()
        fixed = self._goal(goal)
        limits = self._limits(max_speed, max_angular_speed)
        step_x, step_r = self.position_.predictor(), self.orientation_.predictor()
        origin = np.zeros(3)

        def step(x, quat, goal=None):
            gx, gq = fixed if goal is None else self._pose(goal, "goal")
            q = self._quat(quat, "quat").tolist()
            r = chart_one(q, gq.tolist())
            v, rdot = step_x(x, gx), step_r(np.array(r), origin)
            w = np.array(rotate_one(q, body_velocity_one(r, rdot.tolist())))
            lam = float(pose_speed_factor(np.array([r]), np.concatenate([v, rdot])[None], *limits)[0, 0]) \
                if limits != (None, None) else 1.0
            return lam * v, lam * w
        return step

    @staticmethod
    def _limits(max_speed, max_angular_speed) -> tuple:
        return check_limits(max_speed, max_angular_speed)

    def predict(self, X, Q):
        """(v, omega), (m, 3) each, at positions X (m, 3) and orientations Q (m, 4, w x y z): :meth:`predictor`'s."""
        step = self.predictor()
        rows = [step(x, q) for x, q in zip(np.atleast_2d(X), np.atleast_2d(Q))]
        return np.array([v for v, _ in rows]), np.array([w for _, w in rows])

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None,
                max_angular_speed=None, **other) -> PoseTrajectory:
        """Integrate from the pose x0 = (x, y, z, qw, qx, qy, qz) for ``duration`` s; ``perturbations`` (pushes)
        [(t, (dx, dy, dz, wx, wy, wz))]: x += dx and R <- exp(w) R (world rotation vector);
        ``goal_changes`` [(t, goal pose)]. Between events the chart state at the goal in effect is
        integrated and mapped back (module docstring). ``max_speed`` / ``max_angular_speed``: as
        :meth:`predictor` (the same paths, traversed more slowly)."""
        self.refuse(other, "rollout")
        self._check_fitted()
        limits = self._limits(max_speed, max_angular_speed)
        x, q = self._pose(x0, "x0")
        gx, gq = self._goal(goal)
        try:
            pushes = [(float(t), np.asarray(d, dtype=float)) for t, d in perturbations]
            goals = [(float(t), g) for t, g in goal_changes]
        except (TypeError, ValueError):
            raise InputError("pushes and goal_changes must be lists of pairs (time, vector).") from None
        events = sorted([(t, 0, d) for t, d in pushes] +
                        [(t, 1, np.concatenate(self._pose(g, "goal change"))) for t, g in goals], key=lambda e: e[:2])
        if any(not 0 <= e[0] < duration for e in events) or \
                any(k == 0 and (d.shape != (6,) or not np.isfinite(d).all()) for _, k, d in events):
            raise InputError(f"events must lie in [0, duration = {duration}) and pushes be 6 finite numbers "
                             "(dx, dy, dz, wx, wy, wz).")
        ts, P, Q, G, t0 = [], [], [], [], 0.0
        for t_end, kind, data in events + [(float(duration), -1, None)]:
            if t_end > t0:
                traj = self._segment(x, q, gx, gq, t_end - t0, dt, limits)
                keep = slice(1 if ts else 0, None)
                ts.append(t0 + traj.t[keep])
                P.append(traj.pos[keep, :3])
                Q.append(from_chart(traj.pos[:, 3:], gq)[keep])
                G.append(np.tile(np.concatenate([gx, gq]), (len(ts[-1]), 1)))
                x, q, t0 = traj.pos[-1, :3], from_chart(traj.pos[-1:, 3:], gq)[0], t_end
            if kind == 0:
                x = x + data[:3]
                q = (Rotation.from_rotvec(data[3:]) * Rotation.from_quat(q, scalar_first=True)).as_quat(
                    scalar_first=True)
            elif kind == 1:
                gx, gq = data[:3], data[3:]
        return PoseTrajectory(np.concatenate(ts), np.vstack(P), np.vstack(Q), np.vstack(G))

    def _segment(self, x, q, gx, gq, duration, dt, limits):
        """One segment of the chart state from (x, q) towards (gx, gq) (the blocks' integrator)."""
        def field(S, g):
            Sdot = self.field(S, g[:3])
            return Sdot * pose_speed_factor(S[:, 3:], Sdot, *limits)
        atol = ATOL_REL * min(self.position_.scale_, self.orientation_.scale_)
        return integrate(field, np.concatenate([x, chart(q, gq)[0]]), duration=duration,
                         dt=self.dt_ if dt is None else dt, goal=np.concatenate([gx, np.zeros(3)]), atol=atol)

    def excursion_bound(self, x0, goal=None, **other) -> float:
        """The certified bound on max_t |x(t) - x_g| (data units) from the pose x0: the farthest point of
        the position block's reach box (:func:`~sosdyn.lfd.model.reach.reach_box`; inf without a certified
        constant metric). The angle from the goal orientation is bounded by its start value (module
        docstring)."""
        self.refuse(other, "excursion_bound")
        self._check_fitted()
        x, _ = self._pose(x0, "x0")
        gx, _ = self._goal(goal)
        box = reach_box(self.position_, (x - gx + self.goal_pos_)[None]) if self.position_.certified_ else None
        if box is None:
            return float("inf")
        lo, hi = box[0][0] - self.goal_pos_, box[1][0] - self.goal_pos_
        return float(np.linalg.norm(np.maximum(np.abs(lo), np.abs(hi))))

    def score(self, demos: PoseDemonstrations) -> list[dict]:
        """Per demonstration, its reproduction from its first pose (step ``dt_``): position deviation
        (mean / max, data units) and orientation deviation (mean / max, deg), arrival time, final
        position and angle errors, at goal (:func:`~.pose_score.pose_reproduction_table`)."""
        self._check_fitted()
        if not isinstance(demos, PoseDemonstrations):
            raise InputError(f"PoseCDSP.score takes PoseDemonstrations, got {type(demos).__name__}.")
        return pose_reproduction_table(self, demos)

    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the pose demonstrations' first poses, each for ``duration`` s (default HORIZON x its
        demo's duration); without pose demonstrations InputError (a pose model starts from poses)."""
        self._check_fitted()
        if not isinstance(demos, PoseDemonstrations):
            raise InputError("a pose model is drawn with the pose demonstrations it starts from. Try: --demos "
                             "with pose CSVs (t,x,y,z,qw,qx,qy,qz), e.g. the files it was fitted to.")
        runs = [self.rollout(np.concatenate([d.pos[0], d.quat[0]]), duration or HORIZON * d.duration) for d in demos]
        return Reproductions(list(demos), runs, self.goal_pos_, self.names(), self.units_)

    # ------------------------------------------------------------------ evidence and files
    def verify(self, n_samples=None, seed=None) -> PoseCertificateReport:
        """Each block's certificate check (:meth:`CDSP.verify`)."""
        self._check_fitted()
        return PoseCertificateReport(self.position_.verify(n_samples, seed), self.orientation_.verify(n_samples, seed))

    def summary(self) -> list[str]:
        """Both blocks' certificate numbers, the orientation's rate and speed floor, still blocks, and how far
        the end orientations were aligned."""
        self._check_fitted()
        pos, ori = self.position_.summary(), self.orientation_.summary()
        lines = [f"position block: {pos[0]}; orientation block (identity metric: the angle to the goal "
                 f"orientation never increases): {ori[0]}", *pos[1:]]
        lines += [f"the {block} does not move in the demonstrations: it is held at the goal (returns at rate "
                  f"{rate:.3g}/s if pushed)" for block, rate in self.still_.items() if rate is not None]
        floor = self.orientation_.floor_
        zone = f"{np.rad2deg(floor['radius']):.3g} deg" if floor is not None and "radius" in floor else ""
        lines.append(f"orientation block: certified rate {self.orientation_.gamma:.3g}/s" +
                     ("" if floor is None else f"; {describe(floor, zone)}"))
        if hasattr(self, "orientation_moved_deg_"):
            moved = ", ".join(f"{a:.2g}" for a in self.orientation_moved_deg_)
            lines.append(f"end orientations aligned onto their chordal mean by {moved} deg (refused beyond "
                         f"goal_tol_deg {self.goal_tol_deg:g})")
        return lines

    def content(self) -> dict:
        """The pose model file's fields (:mod:`.content`): the goal orientation, the still rates and each
        block's params and state."""
        self._check_fitted()
        return {"goal_tol_deg": self.goal_tol_deg, "goal_quat": self.goal_quat_, "still": self.still_,
                "position": self.position_.content(), "orientation": self.orientation_.content()}

    @classmethod
    def from_content(cls, content: dict) -> PoseCDSP:
        """A pose model (not yet verified) from a file's content: :func:`~.content.pose_fields`, each block a
        CDSP's content, the orientation block the identity-metric, goal-0, warp-free CDSP the angle needs."""
        goal_quat, still, tol = pose_fields(content)
        blocks = {}
        for block in BLOCKS:
            try:
                blocks[block] = CDSP.from_content(content[block])
            except ModelFileError as exc:
                raise ModelFileError(f"{block}: {exc}") from None
        params = {k: v for k, v in blocks["position"].get_params().items()
                  if k != "progress" and not (v is DEFAULTS[k] or v == DEFAULTS[k])}
        model = cls(tol, **params)
        model.position_, model.orientation_ = blocks["position"], blocks["orientation"]
        check_orientation_block(model.orientation_, model.position_)
        model.goal_quat_, model.still_ = goal_quat, still
        return model

    def to_python(self, max_speed=None, max_angular_speed=None, **other) -> str:
        """A standalone module with ``predict_pose(x, quat, goal=None) -> (v, omega)`` (:func:`~sosdyn.lfd.runtime.pose.pose_to_python`)."""
        self.refuse(other, "to_python")
        self._check_fitted()
        return pose_to_python(self, max_speed, max_angular_speed)

    def to_cpp(self, namespace=None, max_speed=None, max_angular_speed=None, **other) -> str:
        """A header-only C++17 ``NS_pose::predict_pose(x, quat, v, omega, goal)`` (:func:`~sosdyn.lfd.runtime.pose.pose_to_cpp`)."""
        self.refuse(other, "to_cpp")
        self._check_fitted()
        return pose_to_cpp(self, "pose_model" if namespace is None else namespace, max_speed, max_angular_speed)

    def iteration_cap(self, rows: list[dict]) -> str | None:
        """As a CDSP's (:meth:`CDSP.iteration_cap`) for one block's fit: :meth:`fit` tags each row with its
        ``block``, and both blocks share ``max_iter`` and ``tol``."""
        return CDSP(**self.cdsp_params).iteration_cap(rows)


def tagged(progress, block: str):
    """``progress`` called with each history row and its ``block`` ("position" or "orientation")."""
    return lambda row: progress({**row, "block": block})


def check_orientation_block(orientation: CDSP, position: CDSP) -> None:
    """ModelFileError unless the orientation block is a 3-D CDSP with the identity metric (``metric`` and
    its W), no warp and goal exactly 0, and the position block is 3-D (the angle argument, docs/theory.md)."""
    M = metric_matrix(orientation)
    if orientation.metric != "identity" or orientation.warp_ is not None or orientation.dim_ != 3 or \
            position.dim_ != 3 or M is None or not np.array_equal(M, M[0, 0] * np.eye(3)) or \
            np.any(orientation.goal_ != 0.0):
        raise ModelFileError("malformed: the orientation block must be a 3-D CDSP with the identity metric, no warp "
                             "and goal 0 (the angle to the goal orientation then never increases), and the position "
                             "block 3-D")

"""PoseCDSP: a certified model of position and orientation as two certified blocks (docs/theory.md, "Poses").

The pose (x, R) is carried by the chart state s = (x, r), r = log(R_g^T R) the rotation vector of the
orientation from the goal orientation R_g (:func:`~sosdyn.lfd.data.poses.chart`). The model is

    xdot = F_x(x)        the certified CDSP of the positions (``position_``, as a position model),
    rdot = F_r(r)        a CDSP of r in the identity metric (``orientation_``, :mod:`~sosdyn.lfd.fit.pose`),

so the position never depends on the orientation: an orientation-only start or a turn of the goal
orientation moves the position by exactly 0. The orientation's certificate makes the geodesic angle
|r| = angle(R, R_g) decrease, d|r|^2/dt <= -gamma |r|^2, along every trajectory, so a state that starts
in the chart (|r| < pi, any orientation but the exact half turn, which has two logarithms and takes
either) never leaves it: every start converges, with no refusal. A block that does not move in the
demonstrations is fitted as a still block (:func:`~sosdyn.lfd.fit.pose.still_block`, ``still_``).

The predictor evaluates one pose in plain floats (:mod:`~sosdyn.lfd.runtime.pose_step`, the same formulas).

Rollout: the chart state is integrated (the CDSP's integrator, absolute tolerance relative to each
block's scale) and mapped by R = R_g exp(r): unit quaternions by construction. Velocities: v = xdot,
and the world angular velocity omega = R J_r(r) rdot (:func:`~sosdyn.lfd.data.poses.body_velocity`).
A goal pose (x_g', R_g') translates the position field and moves the chart: r' = log(R_g'^T R).

Speed limits (``max_speed`` on |v|, data units / s; ``max_angular_speed`` on |omega|, rad / s): the
chart velocity is scaled by lambda = min(1, v_max / |v|, w_max / |omega|) (:func:`pose_speed_factor`, built
on :func:`~sosdyn.lfd.runtime.states.speed_factor`); one positive factor on the whole velocity keeps the
paths and the goal (a time change of the certified system).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.errors import InputError, NotFittedError
from ..data.poses import (GOAL_TOL_DEG, PoseDemonstrations, align_orientations, body_velocity, chart, from_chart,
                          goal_orientation, split_demonstrations)
from ..fit.pose import check_moves, isotropic_demonstrations, orientation_params, still_block
from ..rollout import ATOL_REL, rollout as integrate
from ..runtime.pose_step import body_velocity_one, chart_one, rotate_one
from ..runtime.states import check_max_speed, speed_factor
from .cdsp import CDSP, DEFAULTS
from .fileformat import write_model_file
from .pose_export import pose_to_cpp, pose_to_python
from .pose_score import pose_reproduction_table
from .reach import reach_box
from .state import STATE_FIELDS, state_record

POSE_FORMAT, POSE_VERSION = "sosdyn-pose", 2
BLOCKS = ("position", "orientation")


def pose_speed_factor(R, Sdot, max_speed, max_angular_speed) -> np.ndarray:
    """lambda = min(1, v_max / |v|, w_max / |omega|) (m, 1) at the rotation vectors R (m, 3) for the chart
    velocities Sdot (m, 6): v = sdot_x, |omega| = |R J_r(r) rdot| = |J_r(r) rdot| (R orthogonal)."""
    w = body_velocity(R, Sdot[:, 3:])
    return np.minimum(speed_factor(Sdot[:, :3], max_speed), speed_factor(w, max_angular_speed))


@dataclass
class PoseTrajectory:
    """A pose rollout: ``t`` (T,), ``pos`` (T, 3), ``quat`` (T, 4 unit, w x y z), ``goal`` (T, 7): the goal
    pose in effect at each sample."""

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    goal: np.ndarray


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


class PoseCDSP:
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
        return {"goal_tol_deg": self.goal_tol_deg, **self.cdsp_params}

    def __repr__(self) -> str:
        """``PoseCDSP(goal_tol_deg=20.0, ...)``; fitted, also the goal pose, each block's components and
        whether the certificates passed."""
        args = [f"{k}={v!r}" for k, v in self.get_params().items()]
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
            raise InputError(f"PoseCDSP.fit takes PoseDemonstrations (sosdyn.lfd.data.poses.load_pose_demos), "
                             f"got {type(demos).__name__}.")
        goal_quat = goal_orientation(demos)
        aligned, self.orientation_moved_deg_ = align_orientations(demos, goal_quat, self.goal_tol_deg)
        pos, rot = split_demonstrations(aligned, goal_quat)
        still = {"position": still_block(pos, "position"), "orientation": still_block(rot, "orientation")}
        check_moves(still["position"], still["orientation"], demos.name)
        params = {"position": self.cdsp_params, "orientation": orientation_params(self.cdsp_params)}
        goals = {"position": pos.goal, "orientation": np.zeros(3)}
        for block, data in (("position", pos), ("orientation", rot)):
            rate = still[block]
            if rate is not None:
                data = isotropic_demonstrations(3, rate, goals[block], data.units, data.name)
            model = CDSP(**{**params[block], **({"n_components": 1} if rate else {})},
                         progress=self.progress).fit(data)
            if rate is not None or block == "orientation":
                model.goal_ = goals[block]    # exactly (aligned ends, or symmetric synthetic ones: at round-off)
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
    def predictor(self, goal=None, max_speed=None, max_angular_speed=None):
        """``step(x, quat, goal=None) -> (v, omega)``: linear velocity (3,) and world angular velocity
        (3,) at the position x and orientation quat (w x y z), for the goal pose (7-vector; default
        the model's, fixed here or per call); both scaled by one factor so that |v| <= max_speed and
        |omega| <= max_angular_speed (rad/s) when given. Every input is checked (InputError)."""
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
            lam = min(float(speed_factor(v, limits[0])[0]), float(speed_factor(w, limits[1])[0]))
            return lam * v, lam * w
        return step

    @staticmethod
    def _limits(max_speed, max_angular_speed) -> tuple:
        return (check_max_speed(max_speed), check_max_speed(max_angular_speed, "max_angular_speed", "rad/s"))

    def rollout(self, p0, duration, dt=None, goal=None, pushes=(), goal_changes=(), max_speed=None,
                max_angular_speed=None) -> PoseTrajectory:
        """Integrate from the pose p0 = (x, y, z, qw, qx, qy, qz) for ``duration`` s; ``pushes``
        [(t, (dx, dy, dz, wx, wy, wz))]: x += dx and R <- exp(w) R (world rotation vector);
        ``goal_changes`` [(t, goal pose)]. Between events the chart state at the goal in effect is
        integrated and mapped back (module docstring). ``max_speed`` / ``max_angular_speed``: as
        :meth:`predictor` (the same paths, traversed more slowly)."""
        self._check_fitted()
        limits = self._limits(max_speed, max_angular_speed)
        x, q = self._pose(p0, "p0")
        gx, gq = self._goal(goal)
        try:
            events = sorted([(float(t), 0, np.asarray(d, dtype=float)) for t, d in pushes] +
                            [(float(t), 1, np.concatenate(self._pose(g, "goal change"))) for t, g in goal_changes],
                            key=lambda e: e[:2])
        except (TypeError, ValueError):
            raise InputError("pushes and goal_changes must be lists of pairs (time, vector).") from None
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

    def excursion_bound(self, p0, goal=None) -> float | None:
        """The certified bound on max_t |x(t) - x_g| (data units) from the pose p0: the farthest point of
        the position block's reach box (:func:`~sosdyn.lfd.model.reach.reach_box`; None without a certified
        constant metric). The angle from the goal orientation is bounded by its start value (module
        docstring)."""
        self._check_fitted()
        x, _ = self._pose(p0, "p0")
        gx, _ = self._goal(goal)
        box = reach_box(self.position_, (x - gx + self.goal_pos_)[None]) if self.position_.certified_ else None
        if box is None:
            return None
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

    # ------------------------------------------------------------------ evidence and files
    def verify(self, n_samples=None, seed=None) -> PoseCertificateReport:
        """Each block's certificate check (:meth:`CDSP.verify`)."""
        self._check_fitted()
        return PoseCertificateReport(self.position_.verify(n_samples, seed), self.orientation_.verify(n_samples, seed))

    def save(self, path, key=None):
        """The pose model file: the goal orientation, the still rates, and each block's params and state."""
        self._check_fitted()
        blocks = {b: {"params": dict(m.get_params(), random_state=m.seed_),
                      "state": state_record({k: getattr(m, k) for k in STATE_FIELDS})}
                  for b, m in (("position", self.position_), ("orientation", self.orientation_))}
        content = {"format": POSE_FORMAT, "version": POSE_VERSION, "goal_tol_deg": self.goal_tol_deg,
                   "goal_quat": self.goal_quat_, "still": self.still_, **blocks}
        return write_model_file(content, path, key)

    def export(self, target: str = "python", max_speed=None, max_angular_speed=None, namespace="pose_model") -> str:
        """The standalone source for ``target``: "python" (:func:`~.pose_export.pose_to_python`) or "cpp"
        (:func:`~.pose_export.pose_to_cpp`, in ``namespace``)."""
        self._check_fitted()
        if target == "python":
            return pose_to_python(self, max_speed, max_angular_speed)
        if target == "cpp":
            return pose_to_cpp(self, namespace, max_speed, max_angular_speed)
        raise InputError(f"unknown export target {target!r:.40}. Try: python or cpp.")

"""PoseCDSP: a certified model of position and orientation (docs/theory.md, "Poses"); the pose family
of the model interface (:class:`~.base.MotionModel`).

State s = (x, c r) in R^6: the position x and the rotation vector r = log(R_g^T R) of the
orientation in the chart at the goal orientation R_g (:func:`~sosdyn.lfd.data.pose.chart`),
r scaled by ``rot_factor_`` c = max |x - x_g|_inf / max |r|_inf over the training data (each block
by its own data scale, so the two are commensurate). A :class:`~.cdsp.CDSP` is fitted on the 6-D
demonstrations: positions and orientations coupled, its usual certificate (contraction at rate
gamma in the metric, SOS + sampled check + the warp's numbers) on R^6 with goal (x_g, 0).

Carrying over to rotations: exp_{R_g}: r -> R_g exp(r) is a diffeomorphism of the open ball
|r| < pi onto SO(3) minus the cut locus {angle(R_g^T R) = pi}; a chart trajectory that stays in
the ball is a rotation trajectory, and r -> 0 is R -> R_g. The ball is kept: with a constant
metric M (metric_degree 0) the certificate gives d/dt (u^T M u) <= -gamma u^T M u (u = z, or
phi(z) with a warp), so the ellipsoid through the start is invariant and
|r(t)| <= :func:`chart_bound` (z0) for all t; a rollout whose bound is not below
pi - CHART_MARGIN is checked sample by sample and refused (InputError) if it would leave.

Rollout: the chart state is integrated (the CDSP's integrator) and mapped by R = R_g exp(r):
unit quaternions by construction, no drift off the sphere. Velocities: v = xdot, and the world
angular velocity omega = R J_r(r) rdot (:func:`body_velocity`, the right Jacobian of SO(3):
R^T Rdot = [J_r(r) rdot]_x for R = R_g exp(r)).

Speed limits (``max_speed`` on |v|, data units / s; ``max_angular_speed`` on |omega|, rad / s): the
chart velocity is scaled by one factor lambda, the speed limit's of the joint ratio of |v| / v_max and
|omega| / w_max (:func:`pose_speed_factor`; |v| < v_max, |omega| < w_max);
omega is linear in rdot, so both are scaled by lambda, and one positive factor on the 6-D field
keeps its paths and its goal (the limited system is a time change of the certified one).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from sosdyn.errors import InputError, NotFittedError
from ..data.pose import (CHART_MARGIN, GOAL_TOL_DEG, PoseDemonstrations, align_orientations, chart,
                          chart_demonstrations, goal_orientation)
from ..fit.composite import apply as warp_apply, check as check_warp
from ..fit.params import preset_params
from ..rollout import rollout as integrate
from ..rollout.quality import HORIZON, reproduction_rows
from ..runtime.pose import body_velocity, pose_speed_factor, pose_to_cpp, pose_to_python
from ..runtime.states import check_max_speed
from .base import Layout, MotionModel, Reproductions
from .cdsp import CDSP, DEFAULTS
from .content import POSE_FORMAT, POSE_VERSION, pose_fields
from .reach import metric_matrix, reach_box

#: The numbers of a pose (a start, a goal, a rollout row) and of a push (a world rotation vector w).
POSE_NAMES = ("x", "y", "z", "qw", "qx", "qy", "qz")
PUSH_NAMES = ("dx", "dy", "dz", "wx", "wy", "wz")


def chart_bound(model: CDSP, z0, rot_factor: float) -> float:
    """An upper bound on sup_t |r(t)| from the start z0 (z-units): with u = phi(z) and constant M,
    u^T M u is non-increasing, so |r| = s |z_r| / c <= s / c * sqrt(u0^T M u0) * b with b =
    sqrt(lambda_max(P M^-1 P^T)) (P picks the r block; no warp) or 1 / (sqrt(lambda_min M) b_lo) (warp:
    |z| <= |u| / b_lo, b_lo = prod(1 - l_j) / lam(K) <= sigma_min(J_phi), :mod:`~sosdyn.lfd.fit.composite`).
    inf when M is not constant."""
    M = metric_matrix(model)
    if M is None:
        return np.inf
    z0 = np.asarray(z0, dtype=float)
    if model.warp_ is None:
        level, Minv = float(z0 @ M @ z0), np.linalg.inv(M)
        b = np.sqrt(np.linalg.eigvalsh(Minv[3:, 3:]).max())
    else:
        u0 = warp_apply(z0[None], model.warp_)[0]
        level = float(u0 @ M @ u0)
        lower = check_warp(model.warp_, 1, 0)["singular_bound"]
        b = 1.0 / (np.sqrt(np.linalg.eigvalsh(M).min()) * lower) if lower > 0 else np.inf
    return float(model.scale_ / rot_factor * np.sqrt(max(level, 0.0)) * b)


@dataclass
class PoseTrajectory:
    """A pose rollout: ``t`` (T,), ``pos`` (T, 3), ``quat`` (T, 4 unit, w x y z), ``chart_bounds``:
    the a-priori bound on the angle from the goal (radians) of each segment (between events);
    ``goal_history`` (T, 7): the goal pose in effect at each sample."""

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    chart_bounds: list = field(default_factory=list)
    goal_history: np.ndarray | None = None

    @property
    def states(self) -> np.ndarray:
        """The rows (x, y, z, qw, qx, qy, qz), (T, 7)."""
        return np.hstack([self.pos, self.quat])


class PoseCDSP(MotionModel):
    """Learn a certified pose motion (position and orientation) from :class:`PoseDemonstrations`.

    ``goal_tol_deg``: end orientations further than this from their chordal mean are refused
    (they are aligned to it otherwise, ``orientation_moved_deg_``); every other keyword is a
    :class:`CDSP` parameter of the 6-D chart model ``cdsp_``.
    """

    name = "PoseCDSP"
    file_format, file_version = POSE_FORMAT, POSE_VERSION

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

    def fit(self, demos: PoseDemonstrations) -> PoseCDSP:
        """Goal orientation, aligned ends, the chart, the scale c, then the certified 6-D CDSP."""
        if not isinstance(demos, PoseDemonstrations):
            raise InputError(f"PoseCDSP.fit takes PoseDemonstrations (sosdyn.lfd.data.pose.load_pose_demos), "
                             f"got {type(demos).__name__}.")
        goal_quat = goal_orientation(demos)
        aligned, self.orientation_moved_deg_ = align_orientations(demos, goal_quat, self.goal_tol_deg)
        X = np.vstack([d.pos for d in aligned])
        R = np.vstack([chart(d.quat, goal_quat) for d in aligned])
        pos_scale, rot_scale = np.abs(X - aligned.goal_pos).max(), np.abs(R).max()
        self.rot_factor_ = float(pos_scale / rot_scale) if rot_scale > 0 and pos_scale > 0 else 1.0
        self.goal_quat_ = goal_quat
        self.cdsp_ = CDSP(**self.cdsp_params, progress=self.progress).fit(chart_demonstrations(aligned, goal_quat, self.rot_factor_))
        return self

    # ------------------------------------------------------------------ state and chart
    def _check_fitted(self):
        if not hasattr(self, "cdsp_"):
            raise NotFittedError("this PoseCDSP is not fitted yet; call fit(pose_demos) first")

    @property
    def goal_pos_(self) -> np.ndarray:
        return self.cdsp_.goal_[:3]

    @property
    def certified_(self) -> bool:
        return bool(self.cdsp_.certified_)

    verification_ = property(lambda self: self.cdsp_.verification_, doc="The 6-D chart model's check.")
    history_ = property(lambda self: self.cdsp_.history_, doc="The 6-D chart model's convex steps.")
    units_ = property(lambda self: self.cdsp_.units_, doc="The positions' units.")
    columns_ = None             # pose files are read by their own header rule (x, y, z and a quaternion)

    def _pose(self, p, what: str) -> tuple[np.ndarray, np.ndarray]:
        p = np.asarray(p, dtype=float)
        if p.shape != (7,) or not np.isfinite(p).all():
            raise InputError(f"{what} must be a finite 7-vector (x, y, z, qw, qx, qy, qz), got shape {p.shape}.")
        if not 0.5 < np.linalg.norm(p[3:]) < 1.5:
            raise InputError(f"{what}: the quaternion {p[3:]} is not unit (norm {np.linalg.norm(p[3:]):.3g}).")
        return p[:3], p[3:] / np.linalg.norm(p[3:])

    def _goal(self, goal) -> tuple[np.ndarray, np.ndarray]:
        return (self.goal_pos_, self.goal_quat_) if goal is None else self._pose(goal, "goal")

    def state(self, x, quat, goal_quat) -> np.ndarray:
        """s = (x, c r), r = log(R_g^T R) (refused near the cut locus)."""
        return np.concatenate([x, self.rot_factor_ * chart(quat, goal_quat, "the start orientation")[0]])

    def orientation(self, S, goal_quat) -> np.ndarray:
        """Unit quaternions (w x y z) R_g exp(r) of the chart states S (m, 6)."""
        Rg = Rotation.from_quat(goal_quat, scalar_first=True)
        return (Rg * Rotation.from_rotvec(S[:, 3:] / self.rot_factor_)).as_quat(scalar_first=True)

    # ------------------------------------------------------------------ motion
    def predictor(self, max_speed=None, max_angular_speed=None, goal=None, **other):
        """``step(x, quat, goal=None) -> (v, omega)``: linear velocity (3,) and world angular velocity
        (3,) at the position x and orientation quat (w x y z), for the goal pose (7-vector; default
        the model's, fixed here or per call); both scaled by :func:`pose_speed_factor` so that
        |v| <= max_speed and |omega| <= max_angular_speed (rad/s) when given."""
        self.refuse(other, "predictor")
        self._check_fitted()
        fixed = self._goal(goal)
        limits = self._limits(max_speed, max_angular_speed)
        step6 = self.cdsp_.predictor()
        g6 = self.cdsp_.goal_

        def step(x, quat, goal=None):
            gx, gq = fixed if goal is None else self._pose(goal, "goal")
            x = np.asarray(x, dtype=float)
            s = self.state(x, np.asarray(quat, dtype=float), gq)
            sdot = step6(s - np.concatenate([gx, np.zeros(3)]) + g6)
            sdot = sdot * pose_speed_factor(s[None], sdot[None], self.rot_factor_, *limits)[0]
            r, rdot = s[3:] / self.rot_factor_, sdot[3:] / self.rot_factor_
            R = Rotation.from_quat(gq, scalar_first=True) * Rotation.from_rotvec(r)
            return sdot[:3], R.apply(body_velocity(r, rdot)[0])
        return step

    @staticmethod
    def _limits(max_speed, max_angular_speed) -> tuple:
        return (check_max_speed(max_speed), check_max_speed(max_angular_speed, "max_angular_speed", "rad/s"))

    def rollout(self, x0, duration, dt=None, goal=None, perturbations=(), goal_changes=(), max_speed=None,
                max_angular_speed=None, **other) -> PoseTrajectory:
        """Integrate from the pose x0 = (x, y, z, qw, qx, qy, qz) for ``duration`` s; ``perturbations``
        (pushes) [(t, (dx, dy, dz, wx, wy, wz))]: x += dx and R <- exp(w) R (world rotation vector);
        ``goal_changes`` [(t, goal pose)]. Between events the chart state at the goal in effect is
        integrated and mapped back (module docstring); a segment whose a-priori bound is not below
        pi - CHART_MARGIN and whose samples leave it is refused. ``max_speed`` / ``max_angular_speed``:
        as :meth:`predictor` (the same paths, traversed more slowly)."""
        self.refuse(other, "rollout")
        self._check_fitted()
        limits = self._limits(max_speed, max_angular_speed)
        x, q = self._pose(x0, "x0")
        gx, gq = self._goal(goal)
        events = sorted([(float(t), 0, np.asarray(d, dtype=float)) for t, d in perturbations] +
                        [(float(t), 1, np.asarray(g, dtype=float)) for t, g in goal_changes], key=lambda e: e[:2])
        if any(not 0 <= e[0] < duration for e in events) or any(k == 0 and d.shape != (6,) for _, k, d in events):
            raise InputError(f"events must lie in [0, duration = {duration}) and pushes be 6-vectors (dx, w).")
        ts, P, Q, G, bounds, t0 = [], [], [], [], [], 0.0
        for t_end, kind, data in events + [(float(duration), -1, None)]:
            if t_end > t0:
                traj = self._segment(x, q, gx, gq, t_end - t0, dt, bounds, limits)
                keep = slice(1 if ts else 0, None)
                ts.append(t0 + traj.t[keep])
                P.append(traj.pos[keep, :3])
                Q.append(self.orientation(traj.pos, gq)[keep])
                G.append(np.tile(np.concatenate([gx, gq]), (len(ts[-1]), 1)))
                x, q, t0 = traj.pos[-1, :3], Q[-1][-1] if len(Q[-1]) else q, t_end
            if kind == 0:
                x = x + data[:3]
                q = (Rotation.from_rotvec(data[3:]) * Rotation.from_quat(q, scalar_first=True)).as_quat(
                    scalar_first=True)
            elif kind == 1:
                gx, gq = self._pose(data, "goal change")
        return PoseTrajectory(np.concatenate(ts), np.vstack(P), np.vstack(Q), bounds, np.vstack(G))

    def _segment(self, x, q, gx, gq, duration, dt, bounds, limits):
        s0 = self.state(x, q, gq)
        g6 = np.concatenate([gx, np.zeros(3)])
        bound = chart_bound(self.cdsp_, (s0 - g6) / self.cdsp_.scale_, self.rot_factor_)
        bounds.append(bound)
        model, c = self.cdsp_, self.rot_factor_

        def field(S, g):            # g = g6: the chart goal, r = 0
            Sdot = model.field(S, g)
            return Sdot * pose_speed_factor(S, Sdot, c, *limits)
        traj = integrate(field, s0, duration=duration, dt=model.dt_ if dt is None else dt, goal=g6,
                         scale=model.scale_)
        angle = np.linalg.norm(traj.pos[:, 3:], axis=1) / self.rot_factor_
        if bound >= np.pi - CHART_MARGIN and angle.max() >= np.pi - CHART_MARGIN:
            raise InputError(f"the rollout turns {np.rad2deg(angle.max()):.0f} deg from the goal orientation, "
                             "out of the chart (cut locus at 180 deg). Try: a start nearer the demonstrations.")
        return traj

    # ------------------------------------------------------------------ evidence and files
    def verify(self, n_samples=None, seed=None):
        """The 6-D model's certificate check (:meth:`CDSP.verify`)."""
        self._check_fitted()
        return self.cdsp_.verify(n_samples, seed)

    def content(self) -> dict:
        """The pose model file's fields: the 6-D CDSP's params and state, the goal orientation and c."""
        self._check_fitted()
        return {"goal_tol_deg": self.goal_tol_deg, "goal_quat": self.goal_quat_, "rot_factor": self.rot_factor_,
                **self.cdsp_.content()}

    @classmethod
    def from_content(cls, content: dict) -> PoseCDSP:
        """A pose model (not yet verified) from a file's content (:func:`~.content.pose_fields`)."""
        goal_quat, rot_factor, tol = pose_fields(content)
        model = cls(tol)
        model.cdsp_ = CDSP.from_content({"params": content.get("params"), "state": content.get("state")})
        model.goal_quat_, model.rot_factor_ = goal_quat, rot_factor
        return model

    def accept(self, report) -> None:
        self.cdsp_.accept(report)

    # ------------------------------------------------------------------ the model interface
    def __repr__(self) -> str:
        fitted = "" if not hasattr(self, "cdsp_") else (
            f", fitted: goal {np.array2string(self.goal_pos_, precision=4, separator=', ')} "
            f"{np.array2string(self.goal_quat_, precision=4, separator=', ')}, certified={self.certified_}")
        params = "".join(f", {k}={v!r}" for k, v in self.cdsp_params.items())
        return f"PoseCDSP(goal_tol_deg={self.goal_tol_deg:g}{params}{fitted})"

    def get_params(self) -> dict:
        return {"goal_tol_deg": self.goal_tol_deg, **CDSP(**self.cdsp_params).get_params()}

    @classmethod
    def preset(cls, name: str, **overrides) -> PoseCDSP:
        """An unfitted pose model whose 6-D chart model has the CDSP preset ``name``, then ``overrides``."""
        return cls(**{**preset_params(name), **overrides})

    @classmethod
    def prepare(cls, demos, smooth_window="auto", trim_rest=True, align="auto", max_shift=None):
        """(demos, what reading changed, []): pose demonstrations are fitted without preprocessing, so a
        preprocessing option other than the default is refused."""
        given = [f"{name} ({option})" for name, value, default, option in (
            ("smooth_window", smooth_window, "auto", "--smooth"), ("trim_rest", trim_rest, True, "--trim-rest"),
            ("align", align, "auto", "--align-ends"), ("max_shift", max_shift, None, "--align-ends")) if value != default]
        if given:
            raise InputError(f"{', '.join(given)} {'applies' if len(given) == 1 else 'apply'} to position files; "
                             "these are pose files (quaternion columns), fitted without preprocessing. Try: drop "
                             f"{'it' if len(given) == 1 else 'them'} (--goal-tol-deg bounds the end orientations), "
                             "or --columns x,y,z for a position model.")
        return demos, [f"read: {n}" for n in demos.notes if "renormalised" in n or "sign-flipped" in n], []

    def predict(self, X, Q):
        """(v, omega), (m, 3) each, at positions X (m, 3) and orientations Q (m, 4, w x y z): :meth:`predictor`'s."""
        step = self.predictor()
        rows = [step(x, q) for x, q in zip(np.atleast_2d(X), np.atleast_2d(Q))]
        return np.array([v for v, _ in rows]), np.array([w for _, w in rows])

    def score(self, demos) -> list[dict]:
        """Per demonstration, its rollout from its first pose for HORIZON x its duration (step ``dt_``),
        scored on the positions as :meth:`CDSP.score`, with ``final_angle_deg`` (to the goal orientation)."""
        self._check_fitted()
        dt = self.cdsp_.dt_
        runs = [self.rollout(np.concatenate([d.pos[0], d.quat[0]]), HORIZON * d.duration, dt=dt) for d in demos]
        rows = reproduction_rows(demos, [r.pos for r in runs], self.goal_pos_, dt)
        for row, run in zip(rows, runs):
            row["final_angle_deg"] = float(np.rad2deg(2 * np.arccos(min(1.0, abs(run.quat[-1] @ self.goal_quat_)))))
        return rows

    def excursion_bound(self, x0, goal=None, **other) -> float:
        """A certified bound on max_t |x(t) - goal position| from the pose x0: the position block of the
        6-D chart model's reach box (:func:`~.reach.reach_box`); inf when its metric is not constant."""
        self.refuse(other, "excursion_bound")
        self._check_fitted()
        x, q = self._pose(x0, "x0")
        gx, gq = self._goal(goal)
        box = reach_box(self.cdsp_, (self.state(x, q, gq) - np.concatenate([gx, np.zeros(3)]) + self.cdsp_.goal_)[None])
        if box is None:
            return float("inf")
        lo, hi = (b[0, :3] - self.goal_pos_ for b in box)
        return float(np.linalg.norm(np.maximum(-lo, hi)))

    def to_python(self, max_speed=None, max_angular_speed=None, **other) -> str:
        """A standalone module with ``predict_pose(x, quat, goal=None) -> (v, omega)`` (:func:`~sosdyn.lfd.runtime.pose.pose_to_python`)."""
        self.refuse(other, "to_python")
        return pose_to_python(self, max_speed, max_angular_speed)

    def to_cpp(self, namespace=None, max_speed=None, max_angular_speed=None, **other) -> str:
        """A header-only C++17 ``NS_pose::predict_pose(x, quat, v, omega, goal)`` (:func:`~sosdyn.lfd.runtime.pose.pose_to_cpp`)."""
        self.refuse(other, "to_cpp")
        return pose_to_cpp(self, "pose_model" if namespace is None else namespace, max_speed, max_angular_speed)

    def names(self) -> tuple[str, ...]:
        return POSE_NAMES[:3]

    def layout(self) -> Layout:
        return Layout(POSE_NAMES, (PUSH_NAMES,), POSE_NAMES, POSE_NAMES)

    def reproductions(self, demos=None, duration=None) -> Reproductions:
        """Rollouts from the pose demonstrations' first poses, each for ``duration`` s (default HORIZON x
        its demo's duration); without pose demonstrations InputError (a pose model starts from poses)."""
        self._check_fitted()
        if not isinstance(demos, PoseDemonstrations):
            raise InputError("a pose model is drawn with the pose demonstrations it starts from. Try: --demos "
                             "with pose CSVs (t,x,y,z,qw,qx,qy,qz), e.g. the files it was fitted to.")
        runs = [self.rollout(np.concatenate([d.pos[0], d.quat[0]]), duration or HORIZON * d.duration) for d in demos]
        return Reproductions(list(demos), runs, self.goal_pos_, self.names(), self.units_)

    def summary(self) -> list[str]:
        """The 6-D chart model's certificate lines, and how far the end orientations were aligned."""
        lines = [f"{self.cdsp_.summary()[0]}; on the 6-D chart state (position, rotation vector)",
                 *self.cdsp_.summary()[1:]]
        if hasattr(self, "orientation_moved_deg_"):
            moved = ", ".join(f"{a:.2g}" for a in self.orientation_moved_deg_)
            lines.append(f"end orientations aligned onto their chordal mean by {moved} deg (refused beyond "
                         f"goal_tol_deg {self.goal_tol_deg:g})")
        return lines

    def iteration_cap(self, rows: list[dict]) -> str | None:
        """As the 6-D chart model's (:meth:`CDSP.iteration_cap`): its rows are this fit's."""
        return CDSP(**self.cdsp_params).iteration_cap(rows)

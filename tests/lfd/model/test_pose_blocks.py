"""PoseCDSP's blocks when one does not move (issue 35): an orientation that never changes is held (the
position model alone decides the motion, nothing is scaled by round-off), a pure rotation in place is
fitted with the position held, demos that move neither way are refused; and the reproduction table."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sosdyn.errors import DemonstrationError
from sosdyn.evaluation.poses import angles_deg
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations
from sosdyn.lfd.fit.pose import STILL_RATE
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.model.pose import PoseCDSP

T = np.linspace(0.0, 8.0, 160)
GOAL = np.array([0.5, -0.2, 0.3])
Q = Rotation.from_rotvec([0.2, -0.4, 0.1])
PARAMS = dict(n_components=1, warp="none", max_samples=400)


def moving_positions(n=6):
    rng = np.random.default_rng(11)
    return [GOAL + np.exp(-T)[:, None] * rng.normal(size=3) for _ in range(n)]


def turning(n=6):
    rng = np.random.default_rng(12)
    return [(Q * Rotation.from_rotvec(np.exp(-T)[:, None] * rng.uniform(-1, 1, 3))).as_quat(scalar_first=True)
            for _ in range(n)]


def test_orientation_that_never_moves_is_held_and_the_positions_decide():
    pos = moving_positions()
    still = np.tile(Q.as_quat(scalar_first=True), (len(T), 1))
    demos = PoseDemonstrations([PoseDemonstration(T, p, still) for p in pos], "still", "m")
    model = PoseCDSP(**PARAMS).fit(demos)
    assert model.certified_ and model.still_ == {"position": None, "orientation": STILL_RATE / 8.0}
    alone = CDSP(**PARAMS).fit(Demonstrations([Demonstration.from_positions(T, p) for p in pos], "still", "m"))
    for p in pos:                               # 3x the duration: where the position-only model ends
        traj = model.rollout(np.concatenate([p[0], still[0]]), 24.0)
        ref = alone.rollout(p[0], 24.0)
        assert np.linalg.norm(traj.pos[-1] - model.goal_pos_) <= 1e-6 * np.ptp(p) + np.linalg.norm(
            ref.pos[-1] - alone.goal_)
        assert angles_deg(traj.quat, Q.as_quat(scalar_first=True)).max() < 1e-9      # the orientation held
    pushed = model.rollout(np.concatenate([GOAL, (Rotation.from_rotvec([0, 0, 1.0]) * Q).as_quat(scalar_first=True)]),
                           24.0)                # turned away: returns at the declared rate (95 % per duration)
    a = angles_deg(pushed.quat, Q.as_quat(scalar_first=True))
    assert a[np.searchsorted(pushed.t, 8.0)] < 0.06 * a[0] and a[-1] < 0.01


def test_pure_rotation_in_place_is_fitted_with_the_position_held(tmp_path):
    quats = turning()
    demos = PoseDemonstrations([PoseDemonstration(T, np.tile(GOAL, (len(T), 1)), q) for q in quats], "turn", "m")
    model = PoseCDSP(**PARAMS).fit(demos)
    assert model.certified_ and model.still_["position"] is not None and model.still_["orientation"] is None
    loaded = load_model(model.save(tmp_path / "turn.json"))
    for q in quats:
        traj = loaded.rollout(np.concatenate([loaded.goal_pos_, q[0]]), 16.0)     # the held position
        assert np.abs(traj.pos - loaded.goal_pos_).max() == 0.0
        assert angles_deg(traj.quat[-1], model.goal_quat_)[0] < 0.05
    rows = model.score(demos)
    assert all(r["at_goal"] and r["max_dev"] == 0.0 and r["max_dev_deg"] < 3.0 for r in rows)    # 3 deg: a step


def test_demos_that_never_move_are_refused():
    demos = PoseDemonstrations([PoseDemonstration(T, np.tile(GOAL, (len(T), 1)),
                                                  np.tile(Q.as_quat(scalar_first=True), (len(T), 1)))] * 3, "rest")
    with pytest.raises(DemonstrationError, match="never move"):
        PoseCDSP(**PARAMS).fit(demos)


def test_score_reports_both_parts():
    demos = PoseDemonstrations([PoseDemonstration(T, p, q) for p, q in zip(moving_positions(), turning())], "both", "m")
    model = PoseCDSP(**PARAMS).fit(demos)
    rows = model.score(demos)
    assert len(rows) == 6 and all(r["at_goal"] for r in rows)
    for r in rows:           # the known system is reproduced: small deviations in both parts
        assert r["max_dev"] < 0.05 and r["max_dev_deg"] < 2.0 and r["final_angle_deg"] < 1.0
        assert 0 < r["arrival_s"] < 2 * r["duration_s"]

"""Pose data: header detection, renormalisation, sign continuity, goal orientation, alignment, chart."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.pose import (PoseDemonstration, PoseDemonstrations, align_orientations, chart, demo_chart,
                                   goal_orientation, pose_columns, read_pose_csv, sign_continuous)

Q30 = Rotation.from_rotvec([0.0, 0.0, np.pi / 6]).as_quat(scalar_first=True)     # 30 deg about z


def write_csv(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(f"{v:.17g}" for v in r) for r in rows) + "\n")
    return path


def test_header_decides_the_order():
    assert pose_columns(["t", "x", "y", "z", "qw", "qx", "qy", "qz"])[1:] == ([4, 5, 6, 7], 0, "scalar first")
    assert pose_columns(["time", "x", "y", "z", "qx", "qy", "qz", "qw"])[1:] == ([7, 4, 5, 6], 0, "scalar last")


@pytest.mark.parametrize("header", [["t", "x", "y", "z", "qy", "qx", "qz", "qw"],      # neither order
                                    ["t", "x", "y", "z", "q1", "q2", "q3", "q4"],      # unnamed
                                    ["t", "x", "y", "z", "qw", "qx", "qy", "qy"]])     # repeated
def test_ambiguous_headers_refused_with_hint(header):
    with pytest.raises(InputError, match="Try: a header t,x,y,z,qw,qx,qy,qz"):
        pose_columns(header)


def test_scalar_last_file_reads_the_same_rotation(tmp_path):
    q = Q30 * 1.001                                 # slightly off the unit sphere
    rows_last = [[0.1 * k, k, 0, 0, q[1], q[2], q[3], q[0]] for k in range(12)]
    demo, notes = read_pose_csv(write_csv(tmp_path / "a.csv", ["t", "x", "y", "z", "qx", "qy", "qz", "qw"],
                                          rows_last))
    np.testing.assert_allclose(demo.quat, np.tile(Q30, (12, 1)), atol=1e-12)     # renormalised, w x y z
    assert any("scalar last" in n for n in notes) and any("renormalised (largest | |q| - 1 | = 1.00e-03)" in n
                                                          for n in notes)


def test_repeated_stamps_become_one_sample_with_the_mean_pose(tmp_path):
    """A robot log repeats stamps: rows (t, x, q) sharing t become one; x the mean, q the normalised mean of the
    sign-continuous rows (here q and -q of 10 deg and 20 deg turns: the 15 deg turn between them, to the
    chordal mean's accuracy); identical repeats are dropped; a note says so."""
    turn = [Rotation.from_rotvec([0.0, 0.0, np.deg2rad(a)]).as_quat(scalar_first=True) for a in (0.0, 10.0, 20.0, 30.0)]
    rows = [[0.0, 0.0, 0, 0, *turn[0]], [0.1, 1.0, 0, 0, *turn[1]], [0.1, 3.0, 0, 0, *(-turn[2])],
            [0.2, 4.0, 0, 0, *turn[3]], [0.2, 4.0, 0, 0, *turn[3]], [0.3, 5.0, 0, 0, *turn[3]]]
    demo, notes = read_pose_csv(write_csv(tmp_path / "log.csv", ["t", "x", "y", "z", "qw", "qx", "qy", "qz"], rows))
    np.testing.assert_array_equal(demo.t, [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_allclose(demo.pos[:, 0], [0.0, 2.0, 4.0, 5.0])
    angle = np.rad2deg(Rotation.from_quat(demo.quat, scalar_first=True).as_rotvec()[:, 2])
    np.testing.assert_allclose(angle, [0.0, 15.0, 30.0, 30.0], atol=1e-9)    # symmetric pair: exactly between
    assert any("1 identical row(s) dropped and 1 differing row(s) averaged" in n for n in notes)


def test_non_unit_rows_refused(tmp_path):
    rows = [[0.1 * k, k, 0, 0, 2.0, 0, 0, 0] for k in range(12)]
    with pytest.raises(DemonstrationError, match="norm 2"):
        read_pose_csv(write_csv(tmp_path / "b.csv", ["t", "x", "y", "z", "qw", "qx", "qy", "qz"], rows))


def test_sign_flips_to_the_nearer_quaternion():
    q = np.tile(Q30, (6, 1))
    q[[2, 3]] *= -1                                  # a flipped run in the middle
    fixed, flips = sign_continuous(q)
    np.testing.assert_allclose(fixed, np.tile(Q30, (6, 1)))
    assert flips == 2                                # the two flipped samples, first sample's sign kept
    fixed, flips = sign_continuous(-q)
    np.testing.assert_allclose(fixed, -np.tile(Q30, (6, 1)))
    assert flips == 2


def test_goal_is_the_chordal_mean_and_ends_are_aligned():
    ends = [Rotation.from_rotvec([0, 0, a]) for a in (0.1, -0.1, 0.0)]
    demos = PoseDemonstrations([PoseDemonstration(np.arange(10.0), np.zeros((10, 3)),
                                                  np.tile(e.as_quat(scalar_first=True), (10, 1)))
                                for e in ends])
    g = goal_orientation(demos)
    assert Rotation.from_quat(g, scalar_first=True).magnitude() < 1e-12           # symmetric ends: identity
    aligned, moved = align_orientations(demos, g)
    np.testing.assert_allclose(moved, np.rad2deg([0.1, 0.1, 0.0]), atol=1e-9)
    for a, d in zip(aligned, demos):
        np.testing.assert_allclose(a.quat[0], d.quat[0], atol=1e-12)               # starts untouched
        assert np.linalg.norm(chart(a.quat[-1], g)) < 1e-12                        # ends at the goal
    with pytest.raises(DemonstrationError, match=r"goal_tol_deg=6\.3"):
        align_orientations(demos, g, goal_tol_deg=5.0)


def test_demo_chart_refuses_the_cut_locus_and_chart_takes_every_rotation():
    near_pi = Rotation.from_rotvec([0, 0, np.deg2rad(175)]).as_quat(scalar_first=True)
    with pytest.raises(DemonstrationError, match="175.0 deg from the goal"):
        demo_chart(near_pi, [1, 0, 0, 0])
    np.testing.assert_allclose(chart(Q30, [1, 0, 0, 0])[0], [0, 0, np.pi / 6])
    np.testing.assert_allclose(np.linalg.norm(chart(near_pi, [1, 0, 0, 0])), np.deg2rad(175))
    half = Rotation.from_rotvec([0, np.pi, 0]).as_quat(scalar_first=True)       # the half turn: a logarithm of it
    assert np.linalg.norm(chart(half, [1, 0, 0, 0])) == pytest.approx(np.pi)

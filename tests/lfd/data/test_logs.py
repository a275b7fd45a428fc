"""Logs as they come (issue 34 item 3, issue 35 item 6): repeated time stamps, column selection by
name or index, the time column and constant columns refused, the hint for a joint log, one rule for
the ends in Python and in the CLI, data set names, the memory of reading a file."""
import warnings

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import DemonstrationError, InputError, ResourceLimitError
from sosdyn.lfd.data.datasets import DATASETS_DIR
from sosdyn.lfd.data.demonstrations import merge_repeated_stamps
from sosdyn.lfd.data.files import load_demos


def reach(path, header, t, *columns):
    np.savetxt(path, np.column_stack([t, *columns]), delimiter=",", header=",".join(header), comments="")
    return path


def test_merge_repeated_stamps_keeps_one_sample_per_stamp():
    t = np.array([0.0, 0.1, 0.1, 0.2, 0.3, 0.3, 0.3, 0.4])
    X = np.array([[0, 0], [1, 1], [1, 1], [2, 2], [3, 3], [5, 3], [4, 3], [6, 6]], dtype=float)
    t2, X2, dropped, averaged = merge_repeated_stamps(t, X)
    np.testing.assert_array_equal(t2, [0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_array_equal(X2, [[0, 0], [1, 1], [2, 2], [4, 3], [6, 6]])     # 0.3: the mean of 3, 5, 4
    assert (dropped, averaged) == (1, 2)
    back = np.array([0.0, 0.2, 0.1])
    assert merge_repeated_stamps(back, X[:3])[0] is back                             # time going back: untouched


def test_repeated_stamps_in_a_log_are_merged_with_one_note(tmp_path):
    """Before: 'time is not strictly increasing at sample 2' with no way to drop the repeats."""
    t = np.round(np.linspace(0.0, 1.0, 60), 2)
    t[[10, 30, 31]] = t[[9, 29, 29]]                       # a mouse log: three repeated stamps
    x, y = np.cos(3 * t), np.sin(3 * t)
    x[31] += 1e-3                                          # one of them holds another value
    paths = [reach(tmp_path / f"m{k}.csv", ["t", "x", "y"], t, x + k, y) for k in range(2)]
    with warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        demos = load_demos(paths)
    assert [str(n.message) for n in notes] == [
        "repeated time stamps in 2 of 2 demonstrations (first: m0.csv): one sample per stamp kept, 2 identical "
        "row(s) dropped and 4 differing row(s) averaged into their stamp's sample."]
    assert [len(d.t) for d in demos] == [57, 57] and np.all(np.diff(demos[0].t) > 0)
    back = t.copy()
    back[40] = back[38]                                     # time goes back: still refused
    with pytest.raises(DemonstrationError, match="time column 't': time is not strictly increasing at sample 40"):
        load_demos(reach(tmp_path / "back.csv", ["t", "x", "y"], back, x, y))


@pytest.fixture
def joint_log(tmp_path):
    t = np.linspace(0.0, 2.0, 80)
    joints = [np.sin(t + k) * (k + 1) / 7 for k in range(7)]
    names = ["t_us", *(f"panda_joint{k}" for k in range(1, 8)), "gripper_width"]
    return [reach(tmp_path / f"j{d}.csv", names, t * 1e6, *[q + 0.01 * d for q in joints], np.full_like(t, 0.04))
            for d in range(2)]


def test_the_columns_hint_of_a_joint_log_lists_the_joints_only(joint_log):
    """Before: the hint listed gripper_width among the joints."""
    with pytest.raises(DemonstrationError, match=r"Try: .*e\.g\. --columns panda_joint1,panda_joint2,panda_joint3,"
                                                 r"panda_joint4,panda_joint5,panda_joint6,panda_joint7\.$"):
        load_demos(joint_log)


def test_column_selection_takes_names_or_indices(joint_log):
    by_name = load_demos(joint_log, columns="panda_joint1,panda_joint3")
    by_index = load_demos(joint_log, columns="1,3")            # before: "no column named '1'"
    by_int = load_demos(joint_log, columns=[1, 3])
    for other in (by_index, by_int):
        np.testing.assert_array_equal(other[0].pos, by_name[0].pos)


@pytest.mark.parametrize("columns, match", [
    ("t_us,panda_joint1", r"the position columns include 't_us', the time column: a model of it would take time for a "
                          r"coordinate\. Try: .*--columns panda_joint1,"),
    ("0,1", r"the position columns include 't_us', the time column"),
    ("panda_joint1,gripper_width", r"the position column 'gripper_width' holds the same value \(0\.04\) in every sample "
                                   r"of every demonstration: it carries no motion.*Try: leave it out.*--columns "
                                   r"panda_joint1\.$"),
    ("gripper_width", r"'gripper_width' holds the same value"),
])
def test_column_selection_refuses_the_time_column_and_constant_columns(joint_log, columns, match):
    """Before: --columns t_us,x fitted a model whose first coordinate was time, and a constant column a
    'certified' model whose every demo was at the goal."""
    with pytest.raises(InputError, match=match):
        load_demos(joint_log, columns=columns)


@pytest.mark.parametrize("name", [["hammer"], None, 3, b"hammer"])
def test_load_dataset_refuses_what_is_not_one_name(name):
    """Before: load_dataset(['hammer']) raised an untyped TypeError (unhashable list)."""
    with pytest.raises(InputError, match=r"a data set's name is one string.*Try: one of .*hammer"):
        sd.load_dataset(name)


def test_reading_a_file_over_the_memory_limit_is_refused_before_reading(tmp_path):
    t = np.linspace(0.0, 1.0, 2000)
    path = reach(tmp_path / "long.csv", ["t", "x", "y"], t, np.cos(t), np.sin(t))
    with sd.limits(max_bytes=200_000), pytest.raises(ResourceLimitError, match=r"reading .*long\.csv \(.* KiB\) needs "
                                                                                r"about .* over the limit"):
        load_demos(path)

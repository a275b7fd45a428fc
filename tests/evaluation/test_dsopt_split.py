"""The ds-opt protocol's splits: the standard one (train 1-4, test 5-7) and the swapped one (train 4-7,
test 1-3), in sosdyn.evaluation.dsopt and threaded through problems.lasa_dsopt (cache key, meta)."""
from __future__ import annotations

import numpy as np
import pytest

from problems import lasa_dsopt
from sosdyn.errors import InputError
from sosdyn.evaluation.dsopt import SPLITS, evaluate_shape, split
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations


def tagged_demos(T: int = 60) -> Demonstrations:
    """7 demos; demo d runs from (d + 1, 10) to the origin along a straight line, tagged "#d"."""
    s = np.linspace(1.0, 0.0, T)[:, None]
    return Demonstrations([Demonstration(0.01 * np.arange(T), s * [d + 1.0, 10.0],
                                         np.tile([-(d + 1.0), -10.0], (T, 1)) / (0.01 * (T - 1)), f"#{d}")
                           for d in range(7)], "tagged", "mm")


def test_swapped_split_trains_on_4_to_7_and_tests_on_1_to_3():
    train, test = split(tagged_demos(), *SPLITS["swapped"])
    assert [d.source for d in train] == ["#3", "#4", "#5", "#6"]
    assert [d.source for d in test] == ["#0", "#1", "#2"]
    assert train[0].pos.shape == (30, 2)                                   # every 2nd sample kept
    np.testing.assert_array_equal(test[2].pos[1], tagged_demos()[2].pos[2])
    standard = split(tagged_demos(), *SPLITS["standard"])
    assert [d.source for d in standard[0]] == ["#0", "#1", "#2", "#3"]
    assert [[d.source for d in part] for part in split(tagged_demos())] == [
        [d.source for d in part] for part in standard]                     # the default is the standard split


@pytest.mark.parametrize("train, test, match", [((0, 1), (1, 2), "disjoint"), ((), (1,), "non-empty"),
                                                ((0, 7), (1,), "needs 8 demonstrations")])
def test_bad_splits_are_refused(train, test, match):
    with pytest.raises(InputError, match=match):
        split(tagged_demos(), train, test)


def test_evaluate_shape_fits_on_the_swapped_training_demos():
    seen = []

    def fit(train):
        seen.extend(d.source for d in train)
        return lambda X: -X                                              # xdot = -x: straight to the goal
    result = evaluate_shape(fit, tagged_demos(), *SPLITS["swapped"])
    assert seen == ["#3", "#4", "#5", "#6"] and len(result["dtwd_test"]) == 3
    # copy score: the nearest training demo of test demo d (0-2) is demo 3; kept sample k (original
    # 2k) of the two lies at s = 1 - 2k/59 on each, |d - 3| s mm apart: DTWD = |d - 3| sum_k s_k,
    # sum_k s_k = 30 - 870/59, and the mean of |d - 3| over d = 0, 1, 2 is 2.
    assert result["nearest_demo"] == pytest.approx(2 * (30 - 870 / 59), rel=1e-12)


def test_the_split_is_in_the_cache_key_file_name_and_meta(tmp_path):
    kwargs = lasa_dsopt.settings("CDSP plain", 0, True)
    keys = {s: lasa_dsopt.job_key("Line", kwargs, s) for s in SPLITS}
    assert keys["standard"] != keys["swapped"]
    names = {s: lasa_dsopt.cache_file(tmp_path, "Line", "CDSP plain", 0, True, s).name for s in SPLITS}
    assert names == {"standard": "Line__CDSP_plain__s0__quick.json",
                     "swapped": "Line__CDSP_plain__s0__quick__swapped.json"}
    assert "train on demos 4, 5, 6, 7, test on 1, 2, 3" in lasa_dsopt.protocol("swapped")
    assert lasa_dsopt.parse_args(["--split", "swapped"]).split == "swapped"
    assert lasa_dsopt.parse_args([]).split == "standard"
    with pytest.raises(SystemExit):
        lasa_dsopt.parse_args(["--split", "other"])

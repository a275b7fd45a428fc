"""Demonstrations that cannot carry a model, and data that would take unbounded memory (issue 35,
items 3 and 4): refused with a typed error and a hint before any fit, in every family."""
import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import DemonstrationError, ResourceLimitError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations, check_demonstrations
from sosdyn.lfd.data.preprocess import preprocess, resample_uniform


def still_demos(offset=(1.0, 2.0), noise=0.0):
    t = np.linspace(0.0, 2.0, 50)
    rng = np.random.default_rng(0)
    return Demonstrations([Demonstration.from_positions(t, np.tile(offset, (50, 1)) * (1 + noise * rng.normal(size=(50, 2))))
                           for _ in range(2)], "still", "m")


FAMILIES = {"CDSP": lambda: sd.CDSP(n_components=1), "second order": lambda: sd.SecondOrderCDSP(),
            "second order, mixture": lambda: sd.SecondOrderCDSP(field="mixture", n_components=1)}


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("offset, noise", [((1.0, 2.0), 0.0), ((1.0, 2.0), 1e-16), ((0.0, 0.0), 0.0), ((3e6, -1e5), 1e-15)])
def test_demos_that_do_not_move_are_refused_by_every_family(family, offset, noise):
    """Before: CDSP and SecondOrderCDSP both fitted a 'certified' model of round-off (issue 35)."""
    with pytest.raises(DemonstrationError, match=r"demo 0 of 'still': the positions do not move .* Try: check that "
                                                 r"the position columns are the moving ones"):
        FAMILIES[family]().fit(still_demos(offset, noise))


def test_a_small_motion_far_from_the_origin_still_moves():
    t = np.linspace(0.0, 1.0, 50)
    pos = np.array([3e6, -1e5]) + 1e-4 * np.column_stack([t, t ** 2])      # 0.1 mm at 3000 km: 3e-11 relative
    check_demonstrations([Demonstration.from_positions(t, pos)])


def rest_jump_rest(n=40):
    pos = np.zeros((n, 2))
    pos[n // 2:] = [5.0, 3.0]
    return Demonstrations([Demonstration.from_positions(np.linspace(0, 1, n), pos + k) for k in range(2)], "jump")


@pytest.mark.parametrize("smooth", ["auto", 5, "off"])
def test_a_jump_between_two_rests_is_refused_after_trimming_with_a_hint(smooth):
    """Rest, one-sample jump, rest: trimming left 2 samples and smooth_window=5 raised scipy's
    untyped ValueError ('polyorder must be less than window_length')."""
    with pytest.raises(DemonstrationError, match=r"demo 0 \(jump\) keeps 2 of its 40 samples once the rest at its "
                                                 r"ends is trimmed .* Try: drop that demo.*trim_rest=False"):
        preprocess(rest_jump_rest(), smooth_window=smooth)
    preprocess(rest_jump_rest(), smooth_window=smooth, trim_rest=False)       # kept whole: accepted


def gap_demos():
    """40 samples 1 us apart, then one at 500 s: the median step's grid has 5e8 points."""
    t = np.concatenate([np.arange(40) * 1e-6, [500.0]])
    pos = np.column_stack([np.linspace(0, 1, 41), np.linspace(0, 2, 41) ** 2])
    return Demonstrations([Demonstration.from_positions(t, pos, f"demo{k}.csv") for k in range(2)], "gap", "m")


def test_a_resampling_grid_over_the_memory_limit_is_refused_before_allocation():
    """Before: an untyped MemoryError (3.7 GiB for the first array, ~20 GiB in all) or the OOM killer."""
    pattern = (r"resampling demo0.csv to uniform time steps \(5e\+08 points of the median step 1e-06 s over 500 s; its "
               r"steps range from 1e-06 to 500 s\) needs about .* GiB, over the limit of 4.0 GiB\. Try: if the long "
               r"step is a gap in the recording .* sosdyn.set_limits\(max_bytes=\.\.\.\) \(the sosdyn command: "
               r"SOSDYN_MAX_BYTES=\.\.\. in the environment\)")
    with pytest.raises(ResourceLimitError, match=pattern):
        resample_uniform(gap_demos()[0])
    with pytest.raises(ResourceLimitError, match=pattern):
        preprocess(gap_demos())
    for family in ("second order", "second order, mixture"):
        with pytest.raises(ResourceLimitError, match=pattern):
            FAMILIES[family]().fit(gap_demos())
    with sd.limits(max_bytes=2**20), pytest.raises(ResourceLimitError, match="over the limit of 1.0 MiB"):
        resample_uniform(Demonstration.from_positions(np.r_[np.arange(40) * 1e-3, 100.0],
                                                      np.linspace(0, 1, 41)[:, None]))

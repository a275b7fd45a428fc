"""Event parsing and ordering, and the input checks every integrator shares."""

import numpy as np
import pytest

from sosdyn.errors import InputError
from sosdyn.lfd.rollout import as_positive, as_vector, check_rollout_size, parse_events


def test_events_are_ordered_by_time_goal_changes_first_at_equal_times():
    events = parse_events([(2.0, [1.0, 0.0]), (0.5, [0.0, 1.0])], [(2.0, [5.0, 5.0]), (1.0, [4.0, 4.0])],
                          n=2, duration=3.0)
    assert [(t, kind) for t, kind, _ in events] == [(0.5, "push"), (1.0, "goal_change"),
                                                     (2.0, "goal_change"), (2.0, "push")]
    np.testing.assert_array_equal(events[2][2], [5.0, 5.0])
    assert parse_events((), (), n=2, duration=1.0) == []


@pytest.mark.parametrize("pushes, message", [
    ([(True, [1.0, 0.0])], "not inside"),
    ([(3.5, [1.0, 0.0])], "not inside"),
    ([(1.0, [1.0, 0.0, 0.0])], r"push 0 vector has shape \(3,\)"),
    ("abc", "must be a list of pairs"),
    ([(1.0,)], "must be a pair"),
])
def test_bad_events(pushes, message):
    with pytest.raises(InputError, match=message):
        parse_events(pushes, (), n=2, duration=3.0)


def test_shared_checks():
    np.testing.assert_array_equal(as_vector([1, 2], 2, "x0"), [1.0, 2.0])
    assert as_positive(np.float32(0.5), "dt") == 0.5
    for bad in (0, -1.0, np.inf, True, None, "1"):
        with pytest.raises(InputError, match="dt must be a finite number > 0"):
            as_positive(bad, "dt")
    assert check_rollout_size(1.0, 0.3, 2) == 4          # round(3.33) + 1

"""problems.lattice: the cached field answers exactly on its plot lattice, nowhere else."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from problems.lattice import CachedField, field_on_lattice, lattice_points, plot_bounds


class _Demos(list):
    goal = np.array([0.0, 0.0])


def test_plot_bounds_is_the_square_padded_box():
    demos = _Demos([SimpleNamespace(pos=np.array([[0.0, 0.0], [4.0, 1.0]]))])
    assert plot_bounds(demos) == pytest.approx([-0.4, 4.4, -1.9, 2.9])     # side 4, pad 0.4, centred
    assert plot_bounds(demos, [np.array([[0.0, 10.0]])]) == pytest.approx([-4.0, 8.0, -1.0, 11.0])  # side 10


def test_cached_field_round_trip():
    model = SimpleNamespace(predict=lambda X: np.column_stack([-X[:, 1], X[:, 0]]))
    spec = field_on_lattice(model, [-1.0, 1.0, 0.0, 2.0], 3)
    P = lattice_points(spec["bounds"], 3)
    assert P[:3].tolist() == [[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]              # x fastest
    field = CachedField(spec)
    np.testing.assert_allclose(field(P), model.predict(P))
    with pytest.raises(ValueError, match="own lattice"):
        field(P + 0.1)

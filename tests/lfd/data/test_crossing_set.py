"""The synthesised crossing set (issue 28): loads by name, is marked synthetic, ends at the origin,
looks like a mouse log (integer px, irregular ms stamps, rest at the goal) and crosses on every shape."""
import numpy as np
import pytest

import sosdyn as sd
from problems.crossing_shapes import SHAPES, generate
from sosdyn.lfd.data.crossing import find_crossings
from sosdyn.lfd.data.datasets import CROSSING_SHAPES, DATASETS, DATASETS_DIR, load_dataset


def test_every_shape_is_shipped_synthetic_and_apart_from_the_real_sets():
    assert set(CROSSING_SHAPES) == set(SHAPES) and len(CROSSING_SHAPES) >= 8
    names = sd.dataset_names(synthetic=True)
    assert sorted(n for n in names if n.startswith("crossing/")) == sorted(f"crossing/{s}" for s in CROSSING_SHAPES)
    assert not set(names) & set(sd.dataset_names(synthetic=False))
    assert set(sd.dataset_names()) == set(names) | set(sd.dataset_names(synthetic=False))
    assert all(DATASETS[n].synthetic for n in names) and "hammer" in sd.dataset_names(synthetic=False)
    assert "MIT License" in (DATASETS_DIR / "crossing" / "LICENSE").read_text()
    assert "Synthetic, not recorded" in (DATASETS_DIR / "crossing" / "README.md").read_text()


def test_e_loads_in_seconds_and_px_as_a_mouse_log():
    demos = load_dataset("crossing/e")
    assert len(demos) == 7 and demos.dim == 2 and demos.units == "px"
    raw = np.loadtxt(DATASETS_DIR / "crossing" / "e" / "demo_00.csv", delimiter=",", skiprows=1)
    assert np.allclose(demos[0].t, raw[:, 0] / 1000) and np.array_equal(demos[0].pos, raw[:, 1:])
    steps = np.diff(raw[:, 0])
    assert steps.min() >= 4 and steps.std() > 1          # jittered ms stamps
    for d in demos:
        assert np.array_equal(d.pos[-1], [0, 0])         # the goal is the origin
        assert np.array_equal(d.pos, np.rint(d.pos))     # integer pixels
        assert np.all(d.pos[-5:] == 0)                   # at rest at the goal: repeated samples


def test_the_shipped_files_are_what_the_seeded_generator_writes():
    data = generate()
    for shape in ("alpha", "cross"):
        for k in (0, len(data[shape]) - 1):
            ms, xy = data[shape][k]
            raw = np.loadtxt(DATASETS_DIR / "crossing" / shape / f"demo_{k:02d}.csv", delimiter=",", skiprows=1)
            assert np.array_equal(raw[:, 0], ms) and np.array_equal(raw[:, 1:], xy)


@pytest.mark.parametrize("shape", CROSSING_SHAPES)
def test_every_shape_crosses_after_preprocessing(shape):
    demos, _ = sd.preprocess(load_dataset(f"crossing/{shape}"))
    found = find_crossings(demos)
    if shape == "cross":                                 # families A (even) and B (odd) meet head-on
        pairs = {(c.a % 2, c.b % 2) for c in found if c.a != c.b}
        assert (0, 1) in pairs or (1, 0) in pairs
        assert all(c.angle_deg > 90 for c in found if c.a % 2 != c.b % 2)
    else:                                                # every demo crosses itself
        assert {c.a for c in found if c.a == c.b} == set(range(len(demos)))

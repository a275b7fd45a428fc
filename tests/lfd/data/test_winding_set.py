"""The synthesised winding set (issue 36): loads by name, is marked synthetic, looks like a mouse log,
is what its seeded generator writes, and winds around the goal without a demo crossing itself."""
import numpy as np
import pytest

import sosdyn as sd
from problems.crossing_shapes import generate
from problems.winding_shapes import SEED, SHAPES, winding_angle
from sosdyn.lfd.data.crossing import find_crossings
from sosdyn.lfd.data.datasets import DATASETS, DATASETS_DIR, WINDING_SHAPES, load_dataset


def test_every_shape_is_shipped_synthetic_and_apart_from_the_real_sets():
    assert set(WINDING_SHAPES) == set(SHAPES) and len(WINDING_SHAPES) == 9
    names = [f"winding/{s}" for s in WINDING_SHAPES]
    assert set(names) <= set(sd.dataset_names(synthetic=True))
    assert not set(names) & set(sd.dataset_names(synthetic=False))
    assert all(DATASETS[n].synthetic for n in names)
    assert "MIT License" in (DATASETS_DIR / "winding" / "LICENSE").read_text()
    assert "Synthetic, not recorded" in (DATASETS_DIR / "winding" / "README.md").read_text()


def test_the_shipped_files_are_what_the_seeded_generator_writes():
    data = generate(SEED, SHAPES)
    for shape in ("spiral180", "loop"):
        for k in (0, len(data[shape]) - 1):
            ms, xy = data[shape][k]
            raw = np.loadtxt(DATASETS_DIR / "winding" / shape / f"demo_{k:02d}.csv", delimiter=",", skiprows=1)
            assert np.array_equal(raw[:, 0], ms) and np.array_equal(raw[:, 1:], xy)


def test_winding_angle_known_answers():
    th = np.linspace(0, 1.5 * np.pi, 50)
    assert winding_angle(np.column_stack([np.cos(th), np.sin(th)])) == pytest.approx(270.0)
    assert winding_angle(np.column_stack([np.cos(th), -np.sin(th)])[::-1]) == pytest.approx(270.0)
    assert winding_angle(np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 0.0]])) == 0.0


@pytest.mark.parametrize("shape", WINDING_SHAPES)
def test_every_demo_winds_round_the_goal_as_a_mouse_log_without_crossing_itself(shape):
    """Integer pixels, jittered ms stamps, ends at rest at the origin; every demo turns at least 160
    degrees about the goal (the tight ones start within a fifth of their farthest distance); after
    preprocessing no demo crosses itself (demos may cross each other near the start)."""
    demos = load_dataset(f"winding/{shape}")
    assert len(demos) == 7 and demos.dim == 2 and demos.units == "px"
    for d in demos:
        assert np.array_equal(d.pos[-1], [0, 0]) and np.array_equal(d.pos, np.rint(d.pos))
        assert np.all(d.pos[-5:] == 0) and np.diff(d.t).min() > 0.004 - 1e-9     # stamps >= 4 ms apart
        assert abs(winding_angle(d.pos)) >= 160
        r = np.linalg.norm(d.pos, axis=1)
        if shape in ("nearhook", "loop", "curl"):
            assert r.max() >= 4 * r[0]
    found = find_crossings(sd.preprocess(demos)[0])
    assert not [c for c in found if c.a == c.b]

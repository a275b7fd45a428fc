"""Demonstrations from CSV / NPY files: layouts, delimiters, decimal commas, headers, time, errors."""

import numpy as np
import pytest

from sosdyn.errors import DemonstrationError, InputError
from sosdyn.lfd.data.files import load_demos
from sosdyn.lfd.data.pose import PoseDemonstrations

# ---------------------------------------------------------------- files

T = np.linspace(0.0, 2.0, 21)
S = 3 * (T / 2) ** 2 - 2 * (T / 2) ** 3
POS = np.column_stack([-8.18 * (1 - S), 4.5 * (1 - S)])        # a straight motion to the origin


def write(tmp_path, name, lines):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def rows(sep, decimal=".", time=True):
    cols = np.column_stack([T, POS]) if time else POS
    return [sep.join(f"{v:.6f}".replace(".", decimal) for v in r) for r in cols]


@pytest.mark.parametrize("sep, decimal", [(",", "."), (";", "."), ("\t", "."), (" ", "."), ("   ", "."),
                                          (";", ","), ("\t", ","), (" ", ",")])
def test_delimiters_and_decimal_commas_read_the_same_numbers(tmp_path, sep, decimal):
    demo = load_demos(write(tmp_path, "d.csv", rows(sep, decimal)))[0]
    np.testing.assert_allclose(demo.t, T, atol=1e-6)
    np.testing.assert_allclose(demo.pos, POS, atol=1e-6)


def test_a_headerless_data_row_is_never_a_header(tmp_path):
    demo = load_demos(write(tmp_path, "d.csv", rows(";")))[0]        # the "0;-8.18;..." file
    assert demo.pos.shape == (21, 2) and demo.pos[0, 0] == pytest.approx(-8.18)


def test_header_names_any_case_and_xyz_style(tmp_path):
    lines = ["TimeStamp;X;Y"] + rows(";")
    demo = load_demos(write(tmp_path, "d.csv", lines))[0]
    np.testing.assert_allclose(demo.pos, POS, atol=1e-6)
    xyz = [f"{t},{x},{y},{-x}" for t, (x, y) in zip(T, POS)]
    d3 = load_demos(write(tmp_path, "d3.csv", ["t,x,y,z"] + xyz))
    assert d3.dim == 3
    np.testing.assert_allclose(d3[0].pos[:, 2], -POS[:, 0])
    with_vel = [f"{t},{x},{y},1,2" for t, (x, y) in zip(T, POS)]
    assert load_demos(write(tmp_path, "v.csv", ["time,x,y,vx,vy"] + with_vel))[0].vel[3].tolist() == [1, 2]
    bom = write(tmp_path, "bom.csv", ["\ufefft,x1,x2"] + rows(","))
    assert load_demos(bom)[0].t[-1] == pytest.approx(2.0)


def test_header_without_time_column_is_an_error_unless_dt_is_given(tmp_path):
    path = write(tmp_path, "x.csv", ["x1,x2"] + rows(",", time=False))
    with pytest.raises(DemonstrationError, match=r"x\.csv: no time column.*\['x1', 'x2'\].*comma.*dt="):
        load_demos(path)
    demo = load_demos(path, dt=0.1)[0]
    np.testing.assert_allclose(demo.t, np.arange(21) * 0.1)
    np.testing.assert_allclose(demo.pos, POS, atol=1e-6)           # x1 is a position, not the time
    xy = load_demos(write(tmp_path, "xy.csv", ["x y"] + rows(" ", time=False)), dt=np.float32(0.1))
    assert xy.dim == 2 and xy[0].t[-1] == pytest.approx(2.0)


def test_dt_and_a_time_column_together_are_refused(tmp_path):
    path = write(tmp_path, "t.csv", ["t,x1,x2"] + rows(","))
    with pytest.raises(InputError, match="both dt = 0.1 and a time column \\('t' in the header\\)"):
        load_demos(path, dt=0.1)
    headerless = write(tmp_path, "h.csv", rows(","))
    with pytest.raises(InputError, match="both dt"):
        load_demos(headerless, dt=0.1, time_column=0)
    assert load_demos(headerless, dt=0.1).dim == 3                  # no time column: all 3 are positions


def test_headerless_file_without_time_says_to_pass_dt(tmp_path):
    path = write(tmp_path, "p.csv", [r.replace("-", "") for r in rows(",", time=False)])  # x1 = 8.18 -> 0
    with pytest.raises(DemonstrationError, match=r"p\.csv.*column 0.*not strictly increasing.*--dt STEP, or dt=STEP"):
        load_demos(path)
    assert load_demos(path, dt=0.1).dim == 2


@pytest.mark.parametrize("dt", [0, 0.0, -0.1, np.nan, np.inf, True, "0.1", np.bool_(True)])
def test_bad_dt_is_refused(tmp_path, dt):
    with pytest.raises(InputError, match="dt must be a finite number > 0"):
        load_demos(write(tmp_path, "x.csv", ["x1,x2"] + rows(",", time=False)), dt=dt)


def test_numpy_scalars_are_accepted_for_numbers(tmp_path):
    path = write(tmp_path, "d.csv", rows(","))
    demos = load_demos(path, dim=np.int64(2), time_column=np.int32(0), goal_tol=np.float32(1.0))
    assert demos.dim == 2
    assert load_demos(write(tmp_path, "x.csv", rows(",", time=False)), dt=np.int64(1))[0].t[-1] == 20
    with pytest.raises(InputError, match="dim"):
        load_demos(path, dim=True)


def test_bad_cell_names_file_line_column_and_delimiter(tmp_path):
    lines = rows(";")
    lines[4] = "0.4;abc;1"
    with pytest.raises(DemonstrationError,
                       match=r"d\.csv: line 5, column 2: 'abc' is not a number "
                             r"\(read with delimiter ';' \(semicolon\)\)"):
        load_demos(write(tmp_path, "d.csv", lines))
    lines = rows(";", ",")
    lines[2] = "0,2;1.234,5;1,0"
    with pytest.raises(DemonstrationError, match=r"line 3, column 2: '1\.234,5'.*thousands.*decimal comma"):
        load_demos(write(tmp_path, "k.csv", lines))


def test_decimal_commas_with_comma_delimiter_are_refused_with_a_hint(tmp_path):
    lines = ["t,x1,x2"] + rows(",", ",")                            # "0,000000,-8,180000,..."
    with pytest.raises(DemonstrationError, match=r"different numbers of columns: line 2 has 6.*header has 3.*"
                                                 r"delimiter ',' \(comma\).*separate the columns by ';'"):
        load_demos(write(tmp_path, "c.csv", lines))
    quoted = ['"' + '","'.join(f"{v:.6f}".replace(".", ",") for v in r) + '"'
              for r in np.column_stack([T, POS])]
    np.testing.assert_allclose(load_demos(write(tmp_path, "q.csv", quoted))[0].pos, POS, atol=1e-6)


def test_no_delimiter_found(tmp_path):
    lines = [r.replace(",", "|") for r in rows(",")]
    with pytest.raises(DemonstrationError,
                       match=r"line 1 reads '0\.000000\|-8\.180000\|4\.500000': no delimiter found"):
        load_demos(write(tmp_path, "pipe.csv", lines))


def test_header_without_positions_names_the_delimiter(tmp_path):
    with pytest.raises(DemonstrationError,
                       match=r"header \['t', 'a', 'b'\] \(read with delimiter '\\t' \(tab\)\)"):
        load_demos(write(tmp_path, "tab.csv", ["t\ta\tb"] + rows("\t")))


# ---------------------------------------------------------------- layouts


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


def test_npy_layouts_any_dimension(tmp_path, make_line_demo):
    d3 = make_line_demo((1, 2, 3), goal=(0, 0, 0))
    np.save(tmp_path / "pos.npy", np.column_stack([d3.t, d3.pos]))
    np.save(tmp_path / "posvel.npy", np.column_stack([d3.t, d3.pos, d3.vel]))
    loaded = load_demos([tmp_path / "pos.npy", tmp_path / "posvel.npy"], dim=3)
    assert loaded.dim == 3 and len(loaded) == 2
    np.testing.assert_allclose(loaded[1].vel, d3.vel)
    d1 = make_line_demo((5,), goal=(0,))
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


# ---------------------------------------------------------------- time units, columns


def reach(unit_factor, header, extra=()):
    """Lines of a 2 s 3-D reach with time in 1/unit_factor s, and extra constant columns."""
    lines = [",".join(header)]
    for t, (x, y) in zip(T, POS):
        lines.append(",".join(f"{v:.15g}" for v in (t / unit_factor + 1.7e9 * (unit_factor == 1e-3), x, y, -x,
                                                        *extra)))
    return lines


@pytest.mark.parametrize("header, kwargs, factor", [
    ("t_ms", {}, 1e-3), ("time_ms", {}, 1e-3), ("t_us", {}, 1e-6), ("time", {"time_units": "ms"}, 1e-3),
    ("time", {"time_units": "us"}, 1e-6), ("t", {}, 1.0), ("timestamp_ms", {"time_units": "ms"}, 1e-3)])
def test_time_units_from_the_header_or_the_option(tmp_path, header, kwargs, factor):
    demo = load_demos(write(tmp_path, "r.csv", reach(factor, [header, "x", "y", "z"])), **kwargs)[0]
    np.testing.assert_allclose(demo.t - demo.t[0], T, atol=1e-6)         # seconds, 2 s long
    seconds = load_demos(write(tmp_path, "s.csv", reach(1.0, ["t", "x", "y", "z"])))[0]
    np.testing.assert_allclose(demo.vel, seconds.vel, atol=1e-6)      # units per second


def test_milliseconds_read_as_seconds_are_refused_with_the_option_to_use(tmp_path):
    path = write(tmp_path, "epoch.csv", reach(1e-3, ["time", "x", "y", "z"]))   # epoch ms, a 2 s reach
    with pytest.raises(DemonstrationError, match=r"lasts 2000 s .*time column 'time' read in s.*--time-units"):
        load_demos(path)
    with pytest.raises(InputError, match="says ms but time_units = 's'"):
        load_demos(write(tmp_path, "ms.csv", reach(1e-3, ["t_ms", "x", "y", "z"])), time_units="s")
    with pytest.raises(InputError, match="time_units must be one of s, ms, us"):
        load_demos(path, time_units="min")


def test_quaternion_columns_give_pose_demos_other_orientations_are_refused(tmp_path):
    half = np.sqrt(0.5)                              # 90 deg about z, written in either order
    path = write(tmp_path, "pose.csv", reach(1.0, ["t", "x", "y", "z", "qx", "qy", "qz", "qw"], (0, 0, half, half)))
    qw_first = write(tmp_path, "wxyz.csv", reach(1.0, ["t", "x", "y", "z", "qw", "qx", "qy", "qz"], (half, 0, 0, half)))
    poses = load_demos([path, qw_first], units="m")
    assert isinstance(poses, PoseDemonstrations) and len(poses) == 2 and poses.units == "m"
    for d in poses:
        np.testing.assert_allclose(d.quat, np.tile([half, 0, 0, half], (len(d.t), 1)), atol=1e-12)   # w x y z
        np.testing.assert_allclose(d.pos[:, :2], POS, atol=1e-6)
    demo = load_demos(path, columns="x,y,z")[0]       # positions selected: a position demonstration
    np.testing.assert_allclose(demo.pos[:, :2], POS, atol=1e-6)
    with pytest.raises(InputError, match="goal_tol apply to position files; these are pose files"):
        load_demos(path, goal_tol=0.1)
    plain = write(tmp_path, "plain.csv", reach(1.0, ["t", "x", "y", "z"]))
    with pytest.raises(InputError, match="plain.csv has no quaternion columns but other files do"):
        load_demos([path, plain])
    euler = write(tmp_path, "rpy.csv", reach(1.0, ["t", "x", "y", "z", "roll", "pitch", "yaw"], (0, 0, 0)))
    with pytest.raises(InputError, match=r"orientation columns \['roll', 'pitch', 'yaw'\].*qw,qx,qy,qz.*--columns x,y,z"):
        load_demos(euler)
    other = write(tmp_path, "grip.csv", reach(1.0, ["t", "x", "y", "z", "gripper"], (0.5,)))
    with pytest.raises(InputError, match=r"columns \['gripper'\] are neither.*columns="):
        load_demos(other)


def test_joint_names_are_mapped_by_columns(tmp_path):
    names = [f"panda_joint{i}" for i in range(1, 8)]
    lines = ["t," + ",".join(names)] + [",".join(f"{v:.6f}" for v in (t, *(x * np.arange(1, 8) / 7)))
                                        for t, (x, _) in zip(T, POS)]
    path = write(tmp_path, "joints.csv", lines)
    with pytest.raises(DemonstrationError, match=r"does not give positions.*--columns panda_joint1,.*panda_joint7"):
        load_demos(path)
    demos = load_demos(path, columns=names)
    assert demos.dim == 7
    np.testing.assert_allclose(demos[0].pos[:, 6], POS[:, 0], atol=1e-6)
    assert load_demos(path, columns=",".join(names[:3])).dim == 3
    with pytest.raises(InputError, match="no column named 'elbow'"):
        load_demos(path, columns=["elbow"])
    with pytest.raises(InputError, match="each position column once"):
        load_demos(path, columns="panda_joint1,panda_joint1")

"""Guards at the edges: demonstration files (delimiters, headers, time), rollout sizes and
inputs, responsibilities far from the data, and a fitted model's predict/rollout there."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

import sosdyn as sd
from sosdyn.errors import DemonstrationError, InputError, ResourceLimitError, SolverError
from sosdyn.lfd.data import load_demos
from sosdyn.lfd.gmm import PositionMixture
from sosdyn.lfd.rollout import check_rollout_size, rollout

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
    with pytest.raises(DemonstrationError, match=r"p\.csv.*column 0.*not strictly increasing.*pass dt="):
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


# ---------------------------------------------------------------- rollout sizes and inputs

GOAL = np.array([1.0, -2.0])


def linear(X, goal):
    return -(X - goal)


def test_rollout_size_is_checked_before_allocating():
    assert check_rollout_size(3.0, 0.01, 2) == 301
    with pytest.raises(ResourceLimitError, match=r"sample count is 1e\+11, over the limit max_rollout_steps="
                                                 r"10000000.*larger dt or a shorter duration"):
        rollout(linear, [0.0, 0.0], duration=1e9, dt=0.01, goal=GOAL)
    with pytest.raises(ResourceLimitError, match="max_rollout_steps"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=1e-9, goal=GOAL)
    with pytest.raises(ResourceLimitError, match="inf"):
        rollout(linear, [0.0, 0.0], duration=1e300, dt=1e-300, goal=GOAL)
    with sd.limits(max_rollout_steps=10**12), \
            pytest.raises(ResourceLimitError, match=r"arrays needs about 5960\.5 GiB.*max_bytes"):
        rollout(linear, [0.0, 0.0], duration=1e9, dt=0.01, goal=GOAL)


def test_rollout_step_limit_boundary():
    with sd.limits(max_rollout_steps=51):
        assert rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL).t.shape == (51,)
    with sd.limits(max_rollout_steps=50), pytest.raises(ResourceLimitError, match="is 51, over the limit"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL)
    with sd.limits(max_bytes=51 * 8 * 8 - 1), pytest.raises(ResourceLimitError, match="max_bytes"):
        rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL)   # 51 x (3*2 + 2) x 8 bytes
    with sd.limits(max_bytes=51 * 8 * 8):
        assert rollout(linear, [0.0, 0.0], duration=1.0, dt=0.02, goal=GOAL).pos.shape == (51, 2)


@pytest.mark.parametrize("kwargs, message", [
    ({"dt": 0}, "dt must be a finite number > 0"),
    ({"dt": None}, "dt must be"),
    ({"dt": np.nan}, "dt must be"),
    ({"dt": True}, "dt must be"),
    ({"duration": True}, "duration must be"),
    ({"duration": np.nan}, "duration must be"),
    ({"x0": [np.inf, 0.0]}, "x0 contains NaN or inf"),
    ({"goal": [1.0]}, r"goal has shape \(1,\)"),
    ({"perturbations": None}, "push events must be a list of pairs"),
    ({"goal_changes": {0.5: [0, 0]}}, "goal_change events must be a list of pairs"),
    ({"perturbations": [(np.nan, [1.0, 0.0])]}, "not inside"),
    ({"perturbations": [(0.5, [1.0, np.nan])]}, "push 0 vector contains NaN"),
])
def test_rollout_inputs(kwargs, message):
    args = {"x0": [0.0, 0.0], "duration": 1.0, "dt": 0.1, "goal": GOAL} | kwargs
    with pytest.raises(InputError, match=message):
        rollout(linear, args.pop("x0"), **args)


def test_numpy_scalars_accepted_by_rollout():
    traj = rollout(linear, [0.0, 0.0], duration=np.float32(1.0), dt=np.float64(0.1), goal=GOAL)
    assert traj.t.shape == (11,)
    np.testing.assert_allclose(traj.pos[-1], GOAL * (1 - np.exp(-1.0)), atol=1e-5)


def test_blow_ups_raise_a_typed_error_never_nan():
    with pytest.raises(SolverError, match=r"at t = 0\.99.*blew up") as info:     # xdot = x^2: x = 1/(1-t)
        rollout(lambda X, g: X ** 2, [1.0], duration=2.0, dt=0.1, goal=[0.0])
    assert info.value.status == "solver_error"
    with pytest.raises(SolverError, match="not finite at t = 0"):  # a push to inf
        rollout(linear, [1e308, 0.0], duration=1.0, dt=0.1, goal=GOAL, perturbations=[(0.0, [1e308, 0])])


# ---------------------------------------------------------------- responsibilities far from the data


def two_gaussians(weights=(0.5, 0.5)):
    return PositionMixture(np.array(weights), np.array([[0.0, 0.0], [10.0, 0.0]]),
                           np.array([np.eye(2), 4 * np.eye(2)]))


def test_responsibilities_equal_the_density_ratio_near_the_data():
    mix = two_gaussians((0.3, 0.7))
    X = np.array([[0.0, 0.0], [5.0, 1.0], [12.0, -3.0], [-4.0, 2.0]])
    dens = np.column_stack([w * multivariate_normal(m, c).pdf(X)
                            for w, m, c in zip(mix.weights, mix.means, mix.covariances)])
    np.testing.assert_allclose(mix.responsibilities(X), dens / dens.sum(axis=1, keepdims=True), rtol=1e-12)


def test_far_from_the_data_the_mahalanobis_nearest_component_takes_all():
    mix = two_gaussians((0.99, 0.01))     # component 1 is wider: nearest in Mahalanobis distance far away
    X = np.array([[1e150, 0.0], [1e160, 0.0], [-1e300, 5.0], [1.7e308, -1.7e308], [0.0, -1e200]])
    h = mix.responsibilities(X)
    np.testing.assert_array_equal(h, np.tile([0.0, 1.0], (5, 1)))
    thin = PositionMixture(np.array([0.5, 0.5]), np.zeros((2, 2)), np.array([np.diag([100.0, 0.01]), np.eye(2)]))
    np.testing.assert_array_equal(thin.responsibilities(np.array([[1e200, 0.0], [0.0, 1e200]])), [[1, 0], [0, 1]])
    np.testing.assert_allclose(thin.log_mahalanobis(np.array([[1e200, 0.0]])), [[np.log(1e199), np.log(1e200)]])


def test_responsibilities_refuse_nan_rows():
    with pytest.raises(InputError, match=r"row 1 = \[nan  0\.\] is not finite"):
        two_gaussians().responsibilities(np.array([[0.0, 0.0], [np.nan, 0.0]]))


# ---------------------------------------------------------------- a fitted model far away


def line_demos(n=2):
    t = np.linspace(0, 3, 60)
    demos = [sd.Demonstration(t, np.outer(np.exp(-t), s), -np.outer(np.exp(-t), s))
             for s in ([5.0, 3.0], [-4.0, 6.0], [3.0, -5.0])]
    return sd.Demonstrations(demos, "lines", "m")


@pytest.fixture(scope="module")
def linear_model():
    return sd.CDSP(n_components=2, gamma=0.5).fit(line_demos())


@pytest.fixture(scope="module")
def cubic_model():
    return sd.CDSP(n_components=1, gamma=0.5, field_degree=3).fit(line_demos())


def test_predict_far_away_is_finite_or_a_typed_error(linear_model, cubic_model):
    for x in (1e160, 1e300):
        v = linear_model.predict([x, -x])
        assert np.isfinite(v).all() and np.abs(v).max() > 0.1 * x      # xdot ~ -x: it points home
    assert np.isfinite(cubic_model.predict([1e50, -1e50])).all()
    with pytest.raises(InputError, match=r"overflows.*Try:"):
        cubic_model.predict([1e160, -1e160])


def test_model_rollout_dt_and_size(linear_model):
    with pytest.raises(ResourceLimitError, match="max_rollout_steps"):
        linear_model.rollout([1.0, 1.0], duration=1e9)
    with pytest.raises(InputError, match="dt must be a finite number > 0"):
        linear_model.rollout([1.0, 1.0], duration=1.0, dt=0)
    traj = linear_model.rollout([1.0, 1.0], duration=np.float32(0.5))
    np.testing.assert_allclose(np.diff(traj.t).mean(), linear_model.dt_, rtol=0.1)

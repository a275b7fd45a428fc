"""The model files of all three families, checked in one place (sosdyn.lfd.model.content): a JSON null
never becomes a NaN that loads as certified, unknown fields are refused by name, and the work a load
will do is bounded from the file's header before it starts (issue 35, items 1 and 2)."""
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import sosdyn as sd
from sosdyn.errors import ModelFileError, ResourceLimitError
from sosdyn.lfd.data.pose import PoseDemonstration, PoseDemonstrations
from sosdyn.lfd.model.fileformat import write_model_file


def pose_demos():
    t, rng = np.linspace(0.0, 12.0, 240), np.random.default_rng(3)
    goal, decay = Rotation.from_rotvec([0.3, -0.5, 0.2]), np.exp(-0.8 * t)[:, None]
    return PoseDemonstrations([PoseDemonstration(t, decay * rng.normal(size=3), (goal * Rotation.from_rotvec(
        decay * rng.uniform(-1, 1, 3))).as_quat(scalar_first=True), f"s{i}") for i in range(8)], "known", "m")


@pytest.fixture(scope="module")
def files(tmp_path_factory, linear_demos, second_order_system):
    """A saved model file of each family."""
    folder = tmp_path_factory.mktemp("families")
    return {"first": sd.CDSP(n_components=2, warp="none").fit(linear_demos).save(folder / "first.json"),
            "pose": sd.PoseCDSP(n_components=1, warp="none", max_samples=400).fit(pose_demos()).save(folder / "pose.json"),
            "second": sd.SecondOrderCDSP(field="mixture", n_components=2, tracking_copies=0, max_iter=3).fit(
                second_order_system[3]).save(folder / "second.json")}


def forged(path, tmp_path, edit):
    """A copy of the file at ``path`` with ``edit(doc)`` applied and its checksum recomputed."""
    doc = json.loads(path.read_text())
    edit(doc)
    return write_model_file({k: v for k, v in doc.items() if k not in ("sha256", "hmac_sha256")}, tmp_path / "f.json")


def put(where, value):
    """An edit setting doc[where[0]][where[1]]... to ``value``."""
    def edit(doc):
        for key in where[:-1]:
            doc = doc[key]
        doc[where[-1]] = value
    return edit


def test_every_family_loads_as_saved(files):
    for kind, path in files.items():
        assert sd.load_model(path).certified_, kind


@pytest.mark.parametrize("kind, where, field", [
    ("second", ["state", "goal", 1], "state.goal"),                 # null -> NaN loaded as certified before
    ("second", ["state", "means", 0, 2], "state.means"),
    ("second", ["state", "M", 0, 0], "state.M"),
    ("second", ["state", "dt"], "state.dt"),
    ("pose", ["goal_quat", 3], "goal_quat"),                         # norm |(1, 0, 0, NaN)| passed before
    ("pose", ["goal_tol_deg"], "goal_tol_deg"),
    ("pose", ["orientation", "state", "goal_", 0], "orientation: malformed: state.goal_"),
    ("first", ["state", "goal_", 0], "state.goal_"),
    ("first", ["state", "mixture_", "means", 0, 0], "state.mixture_.means"),
])
def test_a_null_where_a_number_belongs_is_refused_by_name(files, tmp_path, kind, where, field):
    path = forged(files[kind], tmp_path, put(where, None))
    with pytest.raises(ModelFileError, match=field.replace(".", r"\.")):
        sd.load_model(path)


@pytest.mark.parametrize("kind", ["first", "pose", "second"])
@pytest.mark.parametrize("where", [["comment"], ["state", "comment"]])
def test_unknown_fields_are_refused_by_name(files, tmp_path, kind, where):
    block = ["position"] if kind == "pose" and where[0] == "state" else []     # a pose file's blocks hold the states
    path = forged(files[kind], tmp_path, put(block + where, "added by hand"))
    with pytest.raises(ModelFileError, match=r"unknown field " + r"\.".join(where)):
        sd.load_model(path)


def test_second_order_units_and_columns_are_checked(files, tmp_path):
    with pytest.raises(ModelFileError, match=r"state\.units must be"):
        sd.load_model(forged(files["second"], tmp_path, put(["state", "units"], "m\\n#")))
    with pytest.raises(ModelFileError, match=r"state\.columns"):
        sd.load_model(forged(files["second"], tmp_path, put(["state", "columns"], ["x", "x"])))


def second_order_header(n, K):
    """An edit giving a second-order file the header of an n-D, K-component model."""
    def edit(doc):
        doc["state"]["goal"] = [0.0] * n
        doc["state"]["C"] = [[[0.0] * (2 * n)] * n] * K
    return edit


def test_load_work_is_refused_before_it_starts(files, tmp_path):
    """Over the limits the file is refused from its header, naming the limit and how to raise it;
    with the limit raised, the same (inconsistent) file is refused by its fields instead. The issue's
    file (48-D, 3 components: 23-25 s of exact arithmetic) is over the dimension limit."""
    with pytest.raises(ResourceLimitError, match=r"dimension n is 48, over the limit max_model_dim=32"):
        sd.load_model(forged(files["second"], tmp_path, second_order_header(48, 3)))
    path = forged(files["second"], tmp_path, second_order_header(24, 5))     # (5 + 1) 48^3 = 663552
    with pytest.raises(ResourceLimitError, match=r"6\.64e\+05, over the limit max_exact_work=500000.*"
                                                 r"set_limits\(max_exact_work"):
        sd.load_model(path)
    with sd.limits(max_exact_work=10**6), pytest.raises(ModelFileError, match=r"state\.M must be an array of shape"):
        sd.load_model(path)
    cubic = forged(files["first"], tmp_path, lambda doc: doc["params"].update(field_degree=3, metric_degree=2)
                   or doc["state"].update(dim_=16, n_components_=32))     # measured: ~140 s of sampled check
    with pytest.raises(ResourceLimitError, match=r"over the limit max_sampled_work=3000000000"):
        sd.load_model(cubic)
    wide = forged(files["first"], tmp_path, put(["state", "dim_"], 1000))
    with pytest.raises(ResourceLimitError, match=r"dimension n is 1e\+03, over the limit max_model_dim=32"):
        sd.load_model(wide)
    many = forged(files["pose"], tmp_path, put(["orientation", "state", "n_components_"], 500))
    with pytest.raises(ResourceLimitError, match="max_model_components=32"):
        sd.load_model(many)


def test_families_file_is_required_where_one_is_named(files):
    with pytest.raises(ModelFileError, match="not a sosdyn-pose file"):
        sd.load_pose_model(files["second"])

"""CDSP parameters: every bad value is an InputError before any optimisation; numpy scalars,
Generators and RandomStates are accepted; booleans are not numbers."""
import json

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.fit.params import MAX_SEED, PRESETS, check_solver, resolve_seed
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations
from sosdyn.lfd.model.fileformat import read_model_file, write_model_file


def line_demos(T=60):
    """Two straight demonstrations into the origin: enough for a one-Gaussian fit."""
    t = np.linspace(0.0, 3.0, T)
    demos = []
    for i, start in enumerate(((4.0, 1.0), (-3.0, 2.0))):
        pos = np.outer(np.exp(-t), start)
        demos.append(Demonstration(t, pos, -pos, source=f"d{i}"))
    return Demonstrations(demos, name="lines", units="m")


BAD = [
    (dict(margin=-1e-4), "margin must be a positive finite number"),
    (dict(metric_prox=-1e-3), "metric_prox must be a finite number >= 0"),
    (dict(metric_prox=True), "metric_prox must be a finite number >= 0"),
    (dict(margin="small"), "margin must be a positive finite number"),
    (dict(margin=float("nan")), "margin must be a positive finite number"),
    (dict(gamma=True), "gamma must be a positive finite number"),
    (dict(eps=np.bool_(True)), "eps must be a positive finite number"),
    (dict(tol=float("inf")), "tol must be a positive finite number"),
    (dict(n_components=True), "n_components must be an integer"),
    (dict(n_components="auto"), 'n_components must be an integer >= 1 or "bic"'),
    (dict(max_iter=np.float64(3.0)), "max_iter must be an integer"),
    (dict(max_samples=0), "max_samples must be an integer >= 1"),
    (dict(max_samples=2.5), "max_samples must be an integer >= 1"),
    (dict(verify_samples=10**9), r"verify_samples must be an integer in \[100, 1000000\]"),
    (dict(verify_samples=1), r"verify_samples must be an integer in \[100, 1000000\]"),
    (dict(verify_samples=True), "verify_samples must be"),
    (dict(random_state=-1), "random_state must be None, an integer in"),
    (dict(random_state=2**32), "random_state must be None, an integer in"),
    (dict(random_state="seed"), "random_state must be"),
    (dict(solver=None), "solver must be the name of a conic solver.*CLARABEL"),
    (dict(solver="GUROBI_MAYBE"), r"unknown solver 'GUROBI_MAYBE'; use one of \('CLARABEL', 'SCS'\)"),
    (dict(metric=None), "metric must be one of"),
    (dict(solver_method=["ica"]), "solver_method must be one of"),
    (dict(refine_gmm="yes"), "refine_gmm must be True or False"),
    (dict(allow_uncertified=1), "allow_uncertified must be True or False"),
    (dict(progress=5), "progress must be None or a function"),
]


@pytest.mark.parametrize("kwargs, match", BAD, ids=[f"{next(iter(k))}={next(iter(k.values()))!r}"[:40] for k, _ in BAD])
def test_bad_parameters_raise_input_error_before_any_optimisation(kwargs, match):
    model = sd.CDSP(**kwargs)
    with pytest.raises(sd.InputError, match=match):
        model.fit(line_demos())
    assert not hasattr(model, "history_") and not hasattr(model, "seed_")


def test_numpy_scalars_and_a_generator_are_accepted_and_saved_as_plain_json(tmp_path):
    rng = np.random.default_rng(7)
    expected_seed = int(np.random.default_rng(7).integers(0, MAX_SEED))
    model = sd.CDSP(n_components=np.int64(1), gamma=np.float32(0.5), eps=np.float64(1e-3),
                    max_iter=np.int32(2), max_samples=np.int64(100), verify_samples=np.int64(500),
                    random_state=rng, solver="clarabel", corrective_rounds=np.int64(1),
                    corrective_tau=np.float32(0.5)).fit(line_demos())
    assert model.certified_ and model.verification_.n_samples == 500
    assert model.seed_ == expected_seed
    path = model.save(tmp_path / "m.json")
    params = json.loads(path.read_text())["params"]
    assert params["random_state"] == expected_seed and params["gamma"] == float(np.float32(0.5))
    assert type(params["n_components"]) is int and type(params["corrective_rounds"]) is int
    loaded = sd.load_model(path)
    assert loaded.seed_ == expected_seed and loaded.certified_


def test_seeds_from_every_kind_of_random_state():
    assert resolve_seed(5) == 5 and resolve_seed(np.int64(9)) == 9
    assert resolve_seed(np.random.RandomState(3)) == resolve_seed(np.random.RandomState(3))
    assert 0 <= resolve_seed(None) <= MAX_SEED
    sd.CDSP(random_state=np.random.RandomState(0)).check_params()
    sd.CDSP(random_state=None, max_samples=None, solver="scs").check_params()
    check_solver("scs")


def test_subsampling_below_the_mixture_size_is_an_input_error():
    with pytest.raises(sd.InputError, match=r"10 samples \(after max_samples\) are too few for 3 "
                                            "Gaussians.*larger max_samples"):
        sd.CDSP(n_components=3, max_samples=10).fit(line_demos())


def test_verify_arguments_are_checked(tmp_path):
    model = sd.CDSP(warp="none", n_components=1, gamma=0.5, max_iter=1, verify_samples=200).fit(line_demos())
    assert model.verify().n_samples == 200
    with pytest.raises(sd.InputError, match="n_samples must be an integer in"):
        model.verify(n_samples=0)
    with pytest.raises(sd.InputError, match="n_samples must be an integer in"):
        model.verify(n_samples=10**9)
    with pytest.raises(sd.InputError, match="seed must be None or an integer"):
        model.verify(seed=-1)
    with sd.limits(max_bytes=10**6), pytest.raises(sd.ResourceLimitError, match="sampled certificate check"):
        model.verify(n_samples=10**6)


def test_presets_set_their_parameters_and_paper_is_the_former_default():
    paper = sd.CDSP.preset("paper").get_params()
    assert (paper["solver_method"], paper["metric_prox"], paper["n_components"]) == ("alternating", 0.0, 6)
    assert (paper["field_degree"], paper["metric_degree"], paper["gamma"]) == (1, 0, 0.1)
    assert (paper["corrective_rounds"], paper["warp"], paper["speed_floor"]) == (0, "none", "none")  # no refits, warp, floor
    default = sd.CDSP().get_params()                            # "ica", K = 8, warp "auto"
    assert {k: default[k] for k in PRESETS["ica"]} == dict(PRESETS["ica"], n_components=8, warp="auto",
                                                           speed_floor="auto")
    assert (default["corrective_tau"], default["corrective_min_dist"]) == (0.5, 0.02)
    cubic = sd.CDSP.preset("cubic", n_components=4).get_params()
    assert (cubic["field_degree"], cubic["metric_degree"], cubic["n_components"]) == (3, 2, 4)
    assert cubic["corrective_rounds"] == 0 and sd.CDSP.preset("ica").corrective_rounds == 0
    assert cubic["warp"] == sd.CDSP.preset("ica").warp == "none"
    with pytest.raises(sd.InputError, match="unknown preset 'fast'. Try: one of"):
        sd.CDSP.preset("fast")


def test_a_file_written_before_metric_prox_loads_with_the_plain_metric_step(tmp_path):
    model = sd.CDSP(n_components=1, warp="none").fit(line_demos())
    content = read_model_file(model.save(tmp_path / "new.json"), None)
    for name in ("metric_prox", "corrective_rounds", "corrective_tau", "corrective_min_dist", "warp"):
        del content["params"][name]
    del content["state"]["warp_"]
    old = sd.load_model(write_model_file(content, tmp_path / "old.json", None))
    assert old.metric_prox == 0.0 and old.corrective_rounds == 0 and old.warp == "none" and old.certified_
    np.testing.assert_allclose(old.predict([[1.0, 2.0]]), model.predict([[1.0, 2.0]]))

"""Model files: field-by-field validation, bounded reading, canonical checksum, HMAC, atomic saves.

One small model is fitted per module; every other file is forged from its JSON. Forged files
get a recomputed checksum, so what refuses them is the validation, not the checksum.
"""
import errno
import json
import os
import stat

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.model import fileformat as model_io
from sosdyn.lfd.fit.certificate import DEFAULT_SAMPLES


@pytest.fixture(scope="module")
def model(leaf):
    return sd.CDSP(warp="none", n_components=2, gamma=0.5, max_iter=3).fit(leaf.subsample(20))


@pytest.fixture(scope="module")
def saved(model, tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "m.json"
    model.save(path)
    return path


def forge(saved, tmp_path, edit, recompute=True, name="forged.json"):
    """Apply ``edit`` to the saved JSON, recompute the checksum, write it, return the path."""
    doc = json.loads(saved.read_text())
    edit(doc)
    if recompute and model_io.first_bad_value(doc) is None:     # canonical JSON has no NaN/inf
        doc["sha256"] = model_io._digest(doc)
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


def load_refused(path, match, **kw):
    with pytest.raises(sd.ModelFileError, match=match) as info:
        sd.load_model(path, **kw)
    assert type(info.value) is sd.ModelFileError          # never a NotSymmetricError or the like
    assert "Try" in str(info.value)
    return str(info.value)


def setin(keys, value):
    def edit(doc):
        d = doc
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value(d[keys[-1]]) if callable(value) else value
    return edit


def test_round_trip_loads_certified_with_the_library_sample_count(model, saved):
    loaded = sd.load_model(saved)
    assert loaded.certified_ and loaded.verification_.passed
    assert loaded.verification_.n_samples == DEFAULT_SAMPLES == 10_000
    X = np.random.default_rng(0).normal(size=(30, 2)) * 10
    np.testing.assert_array_equal(loaded.predict(X), model.predict(X))
    doc = json.loads(saved.read_text())
    assert doc["version"] == 2 and doc["params"]["random_state"] == model.seed_ == 0


FORGED_CASES = [
    ("goal_ = Infinity", setin(["state", "goal_", 0], float("inf")), r"state\.goal_\[0\] is inf"),
    ("NaN in C_", setin(["state", "C_", 0, 1, 0], float("nan")), r"state\.C_\[0\]\[1\]\[0\] is nan"),
    ("NaN in a Gram matrix", setin(["state", "certificate_", "constraints", 1, "gram", 0, 0], float("nan")),
     r"constraints\[1\]\.gram\[0\]\[0\] is nan"),
    ("scale_ = 0", setin(["state", "scale_"], 0.0), r"state\.scale_ must be a positive"),
    ("dt_ negative", setin(["state", "dt_"], -0.1), r"state\.dt_ must be a positive"),
    ("units_ not a string", setin(["state", "units_"], 5), r"state\.units_ must be a string"),
    ("units_ too long", setin(["state", "units_"], "m" * 500), r"state\.units_ .*at most 32"),
    ("negative mixture weight", setin(["state", "mixture_", "weights"], [1.5, -0.5]), "positive and sum to 1"),
    ("weights not summing to 1", setin(["state", "mixture_", "weights"], [0.5, 0.6]), "sum 1.1"),
    ("indefinite covariance", setin(["state", "mixture_", "covariances", 1], [[1.0, 2.0], [2.0, 1.0]]),
     r"covariances\[1\] is not positive definite"),
    ("asymmetric covariance", setin(["state", "mixture_", "covariances", 0], [[1.0, 0.5], [0.0, 1.0]]),
     r"covariances\[0\] is not symmetric"),
    ("wrong-dimension means", setin(["state", "mixture_", "means"], [[0.0, 0.0, 0.0]] * 2),
     r"means must be an array of shape \(2, 2\), got shape \(2, 3\)"),
    ("C_ of the wrong shape", setin(["state", "C_"], lambda C: C[:1]), r"state\.C_ must be an array of shape \(2, 2, 2\)"),
    ("W_ not symmetric", setin(["state", "W_", 0, 1, 0], 123.0), r"state\.W_ is not symmetric"),
    ("goal_ of the wrong length", setin(["state", "goal_"], [0.0, 0.0, 0.0]), r"state\.goal_ must be an array of shape \(2,\)"),
    ("negative exponent", setin(["state", "field_exps_", 0, 0], -1), "non-negative integers"),
    ("fractional exponent", setin(["state", "field_exps_", 0, 0], 1.5), "non-negative integers"),
    ("a constant term in the fields", setin(["state", "field_exps_", 0], [0, 0]), r"field_exps_ are not the monomials"),
    ("dim_ disagreeing with the arrays", setin(["state", "dim_"], 3), r"shape"),
    ("n_components_ disagreeing with params", setin(["state", "n_components_"], 3), "n_components"),
    ("a Gram matrix of the wrong shape", setin(["state", "certificate_", "constraints", 0, "gram"], [[1.0]]),
     r"constraints\[0\]\.gram must be an array of shape"),
    ("a missing certificate constraint", setin(["state", "certificate_", "constraints"], lambda c: c[:-1]),
     "K \\+ 1 = 3"),
    ("a weakened certificate eps", setin(["state", "certificate_", "eps"], 1e-300), r"eps / 2 = 0.0005"),
    ("boolean in an array", setin(["state", "goal_", 0], True), "numbers only"),
    ("an unknown state field", setin(["state", "extra_"], 1), r"unknown field state\.extra_"),
    ("a missing state field", lambda d: d["state"].pop("dt_"), r"state\.dt_ is missing"),
    ("params.verify_samples = 10**9", setin(["params", "verify_samples"], 10**9), r"verify_samples must be .*\[100, 1000000\]"),
    ("params.verify_samples = 1", setin(["params", "verify_samples"], 1), "verify_samples must be"),
    ("params.gamma = true", setin(["params", "gamma"], True), "gamma must be a positive"),
    ("params.random_state negative", setin(["params", "random_state"], -3), "random_state must be"),
    ("an unknown parameter", setin(["params", "speed"], 2), r"unknown \['speed'\]"),
]


@pytest.mark.parametrize("what, edit, match", FORGED_CASES, ids=[c[0] for c in FORGED_CASES])
def test_forged_fields_are_refused_by_name(saved, tmp_path, what, edit, match):
    load_refused(forge(saved, tmp_path, edit), match)


def test_the_load_check_ignores_the_files_sample_count(saved, tmp_path):
    path = forge(saved, tmp_path, setin(["params", "verify_samples"], 100))
    loaded = sd.load_model(path)
    assert loaded.verify_samples == 100                            # a valid parameter for refits...
    assert loaded.verification_.n_samples == DEFAULT_SAMPLES       # ...that does not thin the load check
    assert loaded.verify().n_samples == 100


def test_checksum_covers_goal_and_scale_but_anyone_can_recompute_it(saved, tmp_path):
    moved = setin(["state", "goal_"], lambda g: [g[0] + 10.0, g[1]])
    load_refused(forge(saved, tmp_path, moved, recompute=False), "fails its checksum")
    load_refused(forge(saved, tmp_path, setin(["state", "scale_"], lambda s: 2 * s), recompute=False),
                 "fails its checksum")
    # recomputed: the certificate (in z-coordinates) still holds, so this loads: the documented
    # limit of a checksum. Only a signature catches it.
    goal = json.loads(saved.read_text())["state"]["goal_"]
    forged = sd.load_model(forge(saved, tmp_path, moved))
    assert forged.certified_ and forged.goal_[0] == goal[0] + 10.0


def test_checksum_is_of_the_canonical_content_not_the_layout(saved, tmp_path):
    doc = json.loads(saved.read_text())
    path = tmp_path / "compact.json"
    path.write_text(json.dumps(dict(reversed(list(doc.items()))), separators=(",", ":")))
    assert sd.load_model(path).certified_
    assert model_io._digest(doc) == doc["sha256"]


def test_hmac_signature(model, saved, tmp_path, monkeypatch):
    signed = tmp_path / "signed.json"
    model.save(signed, key=b"secret")
    assert "hmac_sha256" in json.loads(signed.read_text())
    assert sd.load_model(signed, key=b"secret").certified_
    assert sd.load_model(signed).certified_                        # no key: checksum only
    load_refused(signed, "fails its signature check", key=b"other")
    load_refused(saved, "not signed", key="secret")
    # an edit with a recomputed checksum (the forgery a checksum cannot stop) fails the signature
    moved = forge(signed, tmp_path, setin(["state", "goal_", 0], 1e3))
    load_refused(moved, "fails its signature check", key=b"secret")
    # the environment variable is the default key of save and load
    monkeypatch.setenv("SOSDYN_MODEL_KEY", "env-secret")
    env_signed = tmp_path / "env.json"
    model.save(env_signed)
    assert sd.load_model(env_signed).certified_
    load_refused(signed, "fails its signature check")
    with pytest.raises(sd.InputError, match="key must be non-empty"):
        model.save(tmp_path / "x.json", key=b"")


def test_symlink_to_a_device_fifo_and_directory_are_refused(tmp_path):
    link = tmp_path / "zero.json"
    link.symlink_to("/dev/zero")
    load_refused(link, "character device")
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    load_refused(fifo, "FIFO")                                    # returns: open never blocks
    load_refused(tmp_path, "directory")
    load_refused(tmp_path / "missing.json", "no model file")


def test_size_and_depth_limits(saved, tmp_path):
    with sd.limits(max_file_bytes=1000):
        load_refused(saved, "max_file_bytes")
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100 + "]" * 100)
    load_refused(deep, "nesting depth of its JSON text is 100, over the limit max_json_depth=64")
    deeper = tmp_path / "deeper.json"
    deeper.write_text("[" * 200_000 + "]" * 200_000)
    load_refused(deeper, r"is 2e\+05, over the limit max_json_depth=64")   # refused before parsing
    with sd.limits(max_json_depth=10**6):
        load_refused(deeper, "deeper than Python's parser allows")    # not a RecursionError
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe{")
    load_refused(binary, "corrupt or truncated")
    dup = tmp_path / "dup.json"
    dup.write_text('{"format": "sosdyn-cdsp", "format": "other"}')
    load_refused(dup, "appears twice")


def test_a_failing_save_leaves_the_previous_file_intact(model, saved, tmp_path, monkeypatch):
    path = tmp_path / "m.json"
    path.write_bytes(saved.read_bytes())
    before = path.read_bytes()
    real_fdopen = os.fdopen

    class DiskFull:
        """Writes half of what it is given, then fails like a full disk."""
        def __init__(self, f):
            self.f = f

        def write(self, data):
            self.f.write(data[:len(data) // 2])
            self.f.flush()
            # a reader during the save sees the old, complete model
            assert sd.load_model(path).certified_
            raise OSError(errno.ENOSPC, "No space left on device")

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

    def fdopen(fd, mode="r", *a, **k):
        f = real_fdopen(fd, mode, *a, **k)
        return DiskFull(f) if "w" in mode else f

    monkeypatch.setattr(os, "fdopen", fdopen)
    with pytest.raises(sd.ModelFileError, match="No space left.*previous file there, if any, is unchanged"):
        model.save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]     # no temporary file left
    # a value JSON cannot hold fails before anything is written
    monkeypatch.setitem(model.timings_, "bad", float("nan"))
    with pytest.raises(sd.ModelFileError, match=r"state\.timings_\.bad is nan"):
        model.save(path)
    assert path.read_bytes() == before


def test_save_writes_a_complete_file_with_normal_permissions(model, tmp_path):
    path = tmp_path / "fresh.json"
    model.save(path)
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
    assert json.loads(path.read_text())["sha256"] == model_io._digest(json.loads(path.read_text()))


def test_an_older_version_is_refused_with_advice(saved, tmp_path):
    load_refused(forge(saved, tmp_path, setin(["version"], 1)), "older sosdyn.*refit")

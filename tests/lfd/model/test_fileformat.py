"""The file layer on its own: canonical bytes, digests, bounded parsing, atomic writes (no estimator)."""
import json

import numpy as np
import pytest

import sosdyn as sd
from sosdyn.lfd.model import fileformat as model_io

CONTENT = {"format": model_io.FORMAT, "version": model_io.VERSION, "params": {"a": 1},
           "state": {"C_": np.array([[1.5, -2.0]]), "n": np.int64(3)}}


def test_write_then_read_gives_the_plain_content_back(tmp_path):
    path = model_io.write_model_file(CONTENT, tmp_path / "m.json")
    assert model_io.read_model_file(path) == model_io.plain(CONTENT)
    assert model_io.plain(CONTENT)["state"] == {"C_": [[1.5, -2.0]], "n": 3}
    doc = json.loads(path.read_text())
    assert doc["sha256"] == model_io._digest(doc) and "hmac_sha256" not in doc


def test_canonical_bytes_ignore_layout_and_the_digests():
    a = {"b": 1, "a": [1.0, 2], "sha256": "x"}
    assert model_io.canonical(a) == b'{"a":[1.0,2],"b":1}' == model_io.canonical({"a": [1.0, 2], "b": 1})


def test_signed_files_need_the_key(tmp_path):
    path = model_io.write_model_file(CONTENT, tmp_path / "m.json", key=b"k1")
    assert model_io.read_model_file(path, key="k1")["params"] == {"a": 1}
    with pytest.raises(sd.ModelFileError, match="fails its signature check"):
        model_io.read_model_file(path, key=b"k2")


def test_first_bad_value_names_the_field():
    assert model_io.first_bad_value({"s": {"C": [[1.0, float("nan")]]}}) == ("s.C[0][1]", "nan")
    assert model_io.first_bad_value({"s": [1, "x", None, {"y": 2.0}]}) is None


def test_depth_is_refused_before_parsing_with_the_shared_limit(tmp_path):
    with pytest.raises(sd.ModelFileError, match=r"nesting depth of its JSON text is 65, over the limit "
                                                r"max_json_depth=64\. Try: check it is the right file"):
        model_io.parse_json(b"[" * 65 + b"]" * 65, tmp_path / "x.json")
    assert model_io.parse_json(b"[" * 64 + b"]" * 64, tmp_path / "x.json") is not None
    with sd.limits(max_json_depth=100):
        assert model_io.parse_json(b"[" * 65 + b"]" * 65, tmp_path / "x.json") is not None

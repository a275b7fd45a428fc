"""problems.jsonio: the one JSON cleaner, rounding and writing."""
from __future__ import annotations

import json
import math

import numpy as np

from problems.jsonio import jsonable, rounded, write_json


def test_jsonable_converts_numpy_and_keeps_or_drops_nonfinite():
    obj = {1: np.float64(0.5), "a": [np.int64(3), np.bool_(True), np.array([1.0, np.inf])], "b": (math.nan,)}
    assert jsonable(obj) == {"1": 0.5, "a": [3, True, [1.0, math.inf]], "b": [obj["b"][0]]}
    assert jsonable(obj, finite_only=True) == {"1": 0.5, "a": [3, True, [1.0, None]], "b": [None]}
    assert type(jsonable(np.int64(3))) is int and type(jsonable(np.float32(0.25))) is float


def test_rounded_and_write_json(tmp_path):
    assert rounded(np.array([[1.234567, np.nan], [123456.7, -0.000123456]]), digits=3) == \
        [[1.23, None], [123000.0, -0.000123]]
    path = write_json(tmp_path / "sub" / "x.json", {"v": np.float64(np.inf)})
    assert json.loads(path.read_text()) == {"v": math.inf}
    strict = write_json(tmp_path / "y.json", {"v": np.float64(np.inf)}, finite_only=True)
    assert strict.read_text() == '{\n "v": null\n}\n'

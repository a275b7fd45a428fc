"""Exports cannot carry code (issue 23, item 2): no string from a model reaches a generated file
unescaped, and units' names are restricted at the source."""
import copy
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from sosdyn.errors import InputError, ModelFileError
from sosdyn.lfd.data.demonstrations import Demonstrations
from sosdyn.lfd.model.cdsp import CDSP
from sosdyn.lfd.model.fileformat import _digest
from sosdyn.lfd.model.files import load_model
from sosdyn.lfd.runtime.codegen import PREAMBLE, cpp_string
from sosdyn.lfd.runtime.export_cpp import to_cpp
from sosdyn.lfd.runtime.export_python import to_python

# Each would run code or break the file if it reached the source as text: an encoding declaration
# (line 1 or 2 of a Python file), quotes and newlines that end a literal or a comment, a C++
# comment continued by a trailing backslash, a trigraph, hex digits after an escape, non-ASCII.
HOSTILE = ["coding:unicode_escape\\nprint(1)#", "coding:rot13", "x'''\nprint(1)\n'''", 'mm";} int y = 1; //',
           "m\\", "*/ #include <cstdlib>", "??=", "\\x41bc", "µm²", "\x00\x7f\u2028"]


@pytest.fixture(scope="module")
def fitted(linear_demos):
    return CDSP(n_components=1, warp="none").fit(linear_demos)


def _with_units(model, units):
    m = copy.copy(model)
    m.units_ = units
    return m


@pytest.mark.parametrize("units", HOSTILE, ids=range(len(HOSTILE)))
def test_python_export_of_hostile_units_imports_silently(fitted, tmp_path, units):
    source = to_python(_with_units(fitted, units))
    assert source.splitlines()[:2] == [f"# {line}" for line in PREAMBLE]      # fixed text
    (tmp_path / "field.py").write_text(source, encoding="utf-8")
    probe = ("import json, field; print(json.dumps({'units': field.UNITS, "
             "'v': field.predict([1.0, 2.0]).tolist()}))")
    res = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True,
                         check=True, timeout=60)
    out = json.loads(res.stdout)           # one line: nothing printed at import
    assert out["units"] == units
    np.testing.assert_allclose(out["v"], fitted.predict([1.0, 2.0])[0], rtol=1e-12)


MAIN = r"""#include "model.hpp"
#include <cstdio>
int main() {
  for (const char* c = cdsp_model::units; *c; ++c) std::printf("%02x", static_cast<unsigned char>(*c));
  double x[2] = {1.0, 2.0}, v[2] = {0.0, 0.0};
  const bool ok = cdsp_model::predict(x, v);
  std::printf(" %d %.17g %.17g\n", ok ? 1 : 0, v[0], v[1]);
}
"""


@pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
def test_cpp_export_of_hostile_units_compiles_and_keeps_them(fitted, tmp_path):
    for i, units in enumerate(u for u in HOSTILE if "\x00" not in u):   # a C string ends at NUL
        source = to_cpp(_with_units(fitted, units))
        assert source.splitlines()[:2] == [f"// {line}" for line in PREAMBLE]
        (tmp_path / "model.hpp").write_text(source, encoding="utf-8")
        (tmp_path / "main.cpp").write_text(MAIN)
        exe = tmp_path / f"main{i}"
        subprocess.run(["g++", "-std=c++17", "-Wall", "-Wextra", "-Werror", "-trigraphs", "-o", str(exe),
                        str(tmp_path / "main.cpp")], check=True, capture_output=True, text=True)
        res = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split()
        assert bytes.fromhex(res[0]).decode("utf-8") == units
        np.testing.assert_allclose([float(res[2]), float(res[3])], fitted.predict([1.0, 2.0])[0], rtol=1e-12)
        assert res[1] == "1"


def test_cpp_string_escapes_everything_but_a_safe_alphabet():
    assert cpp_string("mm/s") == '"mm/s"'
    assert cpp_string('a"\\?\n') == '"a\\042\\134\\077\\012"'
    assert cpp_string("µ") == '"\\302\\265"'


@pytest.mark.parametrize("namespace", ["a b", "x;int y", "é", "_x", "", 3, "a" * 65])
def test_cpp_namespace_must_be_an_ascii_identifier(fitted, namespace):
    with pytest.raises(InputError, match="not an ASCII C"):
        to_cpp(fitted, namespace)


def test_unknown_target_is_typed(fitted):
    with pytest.raises(InputError, match="unknown export target 'rust'. Try: one of python, cpp"):
        fitted.export("rust")


@pytest.mark.parametrize("units", ["coding:unicode_escape\\nprint(1)#", "coding=rot13", "m'", 'm"', "m\\",
                                   "#", "a\nb", "m" * 33])
def test_units_outside_the_safe_alphabet_are_refused_at_the_source(linear_demos, tmp_path, fitted, units):
    with pytest.raises(InputError, match="units must be at most 32 characters, each a letter"):
        Demonstrations(list(linear_demos), "x", units)
    path = tmp_path / "m.json"
    fitted.save(path)
    data = json.loads(path.read_text())
    data["state"]["units_"] = units
    data["sha256"] = _digest({k: v for k, v in data.items() if k != "sha256"})
    path.write_text(json.dumps(data))
    with pytest.raises(ModelFileError, match="state.units_ must be at most 32 characters"):
        load_model(path)


@pytest.mark.parametrize("units", ["mm", "m/s", "µm", "m²", "deg (°)", "1e-3 m", "px_raw", ""])
def test_ordinary_units_are_accepted(linear_demos, units):
    assert Demonstrations(list(linear_demos), "x", units).units == units

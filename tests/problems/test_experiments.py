"""problems (the registry) and ``python -m problems``: every make target resolves to a module."""
from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

import problems
from problems.__main__ import main
from sosdyn.errors import InputError


def test_every_make_target_is_an_experiment():
    makefile = (Path(problems.__file__).parents[1] / "Makefile").read_text()
    targets = {m for line in re.findall(r"-m problems (\S+)", makefile) for m in [line]}
    targets |= set(re.search(r"^fig1 .*?:", makefile, re.M).group(0)[:-1].split())
    assert targets <= set(problems.EXPERIMENTS) | {"$@"}
    for module in problems.EXPERIMENTS.values():
        assert callable(importlib.import_module(f"problems.{module}").main)


def test_unknown_experiment(capsys):
    with pytest.raises(InputError, match="no experiment 'fig99'.*fig1"):
        problems.run_experiment("fig99")
    assert main(["fig99"]) == 2 and "no experiment" in capsys.readouterr().err
    assert main([]) == 2

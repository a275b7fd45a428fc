"""Helpers of the export tests (imported by the test modules beside it)."""
import importlib.util

import numpy as np


def max_rel_error(a, b):
    """max over rows of |a - b|_inf / |b|_inf (|b| > 0 in the box: the goal has measure zero)."""
    return float(np.max(np.abs(a - b).max(axis=1) / np.abs(b).max(axis=1)))


def import_source(source, path):
    """The generated Python ``source``, written to ``path`` and imported as a module."""
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(f"exported_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module

"""Shared check of the benchmark smoke tests."""
import math

import pytest


@pytest.fixture
def times_ok():
    """Assert that d[k] is a finite positive time for every key k."""
    def check(d, keys):
        for k in keys:
            v = d[k]
            assert v is not None and math.isfinite(v) and v > 0, (k, v)
    return check

"""Fixtures for the demonstration and rollout tests."""

import pytest

from sosdyn.errors import SosdynError
from sosdyn.lfd import data


@pytest.fixture(scope="session")
def leaf():
    """The LASA Leaf_1 demonstrations; the test is skipped when the LASA data is not installed."""
    try:
        data._lasa_dir()
    except SosdynError as exc:
        pytest.skip(str(exc))
    return data.load_lasa("Leaf_1")

"""Shared test configuration.

Slow checks are marked ``@pytest.mark.slow`` and take the ``full`` fixture: CI runs them in
a reduced form (``full`` is False: fewer samples, smaller models) unless ``TRUSSID_FULL=1``.
"""

import os

import matplotlib
import pytest

matplotlib.use("Agg")  # no display anywhere in the suite


@pytest.fixture(scope="session")
def full() -> bool:
    """True when the full-size form of slow checks should run (``TRUSSID_FULL=1``)."""
    return os.environ.get("TRUSSID_FULL") == "1"


@pytest.fixture
def rng():
    """A seeded generator, so every test is reproducible."""
    import numpy as np

    return np.random.default_rng(20261121)

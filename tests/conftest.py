"""Shared pytest fixtures: a seeded numpy generator (tests must be reproducible)."""

import numpy as np
import pytest


@pytest.fixture
def np_rng():
    return np.random.default_rng(12345)

"""Shared test settings and fixtures."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import armkit

# Kernels compile on first use (numba caches them afterwards), so no per-example deadline.
settings.register_profile("armkit", deadline=None, max_examples=60,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("armkit")

BUILTIN = armkit.robots()


@pytest.fixture(params=BUILTIN)
def any_robot(request) -> armkit.Robot:
    return armkit.robot(request.param)

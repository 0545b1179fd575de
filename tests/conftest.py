"""Shared test settings and fixtures."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings

import armkit

# Kernels compile on first use (numba caches them afterwards), so no per-example deadline.
# CI runs the same examples every time (derandomize); local runs keep exploring new ones.
settings.register_profile("armkit", deadline=None, max_examples=60,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("ci", parent=settings.get_profile("armkit"), derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "armkit")

BUILTIN = armkit.robots()


@pytest.fixture(params=BUILTIN)
def any_robot(request) -> armkit.Robot:
    return armkit.robot(request.param)

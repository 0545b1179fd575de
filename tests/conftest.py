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


@pytest.fixture(scope="session")
def dask_client():
    """A two-worker Dask cluster on loopback (separate processes), shared by the tests of one
    pytest worker; its HTTP server on a free port, as another worker may hold Dask's default."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as cluster, Client(cluster) as client:
        yield client

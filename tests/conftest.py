"""Shared test settings and fixtures."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings

import armkit

# Kernels compile on first use (numba caches them afterwards), so no per-example deadline.
# CI runs the same examples every time (derandomize); local runs keep exploring new ones.
# `pytest` tries each property on 25 examples; `pytest -m slow` (which CI runs too) tries
# every property on 300, beside the long fuzz runs.
settings.register_profile("armkit", deadline=None, max_examples=25,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", parent=settings.get_profile("armkit"), max_examples=300)
for name in ("armkit", "thorough"):
    settings.register_profile(f"{name}-ci", parent=settings.get_profile(name), derandomize=True)
CI = bool(os.environ.get("CI"))


def _slow_run(config) -> bool:
    return (config.option.markexpr or "").strip() == "slow"


def pytest_configure(config):
    profile = "thorough" if _slow_run(config) else "armkit"
    settings.load_profile(f"{profile}-ci" if CI else profile)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """In the slow run, the property tests are run again with many examples."""
    if _slow_run(config):
        for item in items:
            if getattr(getattr(item, "obj", None), "is_hypothesis_test", False):
                item.add_marker(pytest.mark.slow)

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

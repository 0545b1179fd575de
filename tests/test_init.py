"""`import armkit` is cheap: the heavy dependencies load with the calls that need them."""

from __future__ import annotations

import subprocess
import sys

import pytest

import armkit


def modules_after(code: str) -> set[str]:
    script = code + "\nimport sys\nprint(' '.join(sys.modules))"
    done = subprocess.run([sys.executable, "-c", script],
                          check=True, capture_output=True, text=True)
    return set(done.stdout.split())


def test_import_loads_no_heavy_dependency():
    loaded = modules_after("import armkit")
    for heavy in ("numba", "scipy", "pydantic", "yaml", "matplotlib", "pymodbus", "dask",
                  "distributed", "armkit.kinematics", "armkit.trajectory"):
        assert heavy not in loaded, heavy


def test_a_spline_does_not_load_inverse_kinematics():
    loaded = modules_after("import armkit\narmkit.spline([0, 1], [[0.0], [1.0]], 5)")
    assert "armkit.trajectory.splines" in loaded
    assert "armkit.kinematics.ik" not in loaded and "pymodbus" not in loaded


def test_every_exported_name_resolves():
    for name in armkit.__all__:
        assert getattr(armkit, name) is not None, name
    assert set(armkit.__all__) <= set(dir(armkit))


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'fkk'"):
        armkit.fkk  # noqa: B018

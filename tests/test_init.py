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


def test_the_command_line_starts_without_the_heavy_dependencies():
    loaded = modules_after("from armkit.cli import app")      # every command registered
    assert "armkit.cli.calibration" in loaded and "armkit.cli.job" in loaded
    for heavy in ("numba", "scipy", "matplotlib", "plotly", "pymodbus", "dask",
                  "armkit.planning.collision", "armkit.perception.target"):
        assert heavy not in loaded, heavy


def test_a_command_loads_only_its_own_module():
    loaded = modules_after("import sys\nfrom armkit.cli import main\n"
                           "sys.argv = ['armkit', 'fk', 'ur5', '0', '0', '0', '0', '0', '0']\n"
                           "try:\n    main()\nexcept SystemExit:\n    pass")
    assert "armkit.cli.robots" in loaded
    for other in ("armkit.cli.calibration", "armkit.cli.ik", "armkit.cli.job",
                  "armkit.cli.trajectory", "armkit.kinematics.ik"):
        assert other not in loaded, other


def test_each_command_is_in_the_module_main_loads_for_it():
    from armkit.cli import app
    from armkit.cli.command import COMMAND_MODULES, MODULES

    registered = {info.name or info.callback.__name__: info.callback.__module__
                  for info in app.registered_commands}
    assert registered == {name: f"armkit.cli.{module}"
                          for name, module in COMMAND_MODULES.items()}
    assert set(COMMAND_MODULES.values()) == set(MODULES)


def test_no_exported_name_is_shadowed_by_a_module_of_the_same_name():
    """Every submodule imported first, then each package's names read: a function is never
    replaced by the module Python binds to the package when it imports that module."""
    script = """
import importlib, pkgutil, types, armkit
names = ["armkit"] + [info.name for info in pkgutil.walk_packages(armkit.__path__, "armkit.")
                      if info.name != "armkit.__main__"]
for name in names:
    importlib.import_module(name)
for name in names:
    package = importlib.import_module(name)
    for exported in getattr(package, "__all__", ()):
        if isinstance(getattr(package, exported), types.ModuleType):
            print(f"{package.__name__}.{exported}")
"""
    done = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True,
                          text=True)
    assert done.stdout == "", done.stdout

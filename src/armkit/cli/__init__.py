"""The `armkit` command line: `app` and its subcommands, one module per group."""

from armkit.cli.app import app, main
from armkit.cli import (calibration, drives, ik, job, perception, plan,  # noqa: F401 (register
                        robots, trajectory, workspace)                # their commands)

__all__ = ["app", "main"]

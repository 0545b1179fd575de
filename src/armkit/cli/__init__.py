"""The `armkit` command line: `app` and its subcommands, one module per group."""

from armkit.cli.app import app, main
from armkit.cli import (demo, drives, ik, robots, trajectory,  # noqa: F401  (registers
                        workspace)                                # their commands)
from armkit.cli import plan  # noqa: F401,E402

__all__ = ["app", "main"]

"""The `armkit` command line: `app` and its subcommands, one module per group."""

from armkit.cli.app import app, main
from armkit.cli import (drives, ik, job, plan, robots, trajectory,  # noqa: F401  (register
                        workspace)                                 # their commands)

__all__ = ["app", "main"]

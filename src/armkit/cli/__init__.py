"""The `armkit` command line: `app` and its subcommands, one module per group."""

from armkit.cli.app import app, main
from armkit.cli import demo, robots, workspace  # noqa: F401  (registers their commands on app)

__all__ = ["app", "main"]

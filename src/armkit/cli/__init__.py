"""The `armkit` command line: `app` with every command, one module per group, and `main`,
the console script, which loads only the module of the command it runs."""

from armkit.cli.command import main

__all__ = ["app", "main"]


def __getattr__(name: str):
    """`app`, with the commands of every module registered (imported on first use)."""
    if name == "app":
        from armkit.cli.command import app, load_commands

        load_commands()
        return app
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""The `armkit` command: one Typer app, library errors turned into one line and exit 2.

Exit status: 0 success, 1 a result that failed (unreachable target, no path), 2 bad input.
Every command that prints results takes ``--json``: one JSON document on stdout, nothing else.
"""

from __future__ import annotations

import json
import sys
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from typer.core import TyperGroup

from armkit.errors import ArmkitError

EXIT_FAILED, EXIT_BAD_INPUT = 1, 2

stdout = Console(highlight=False, soft_wrap=True)
stderr = Console(stderr=True, highlight=False, soft_wrap=True)


class _Group(TyperGroup):
    """Catches the library's errors once, at the edge: one stderr line, exit 2, no traceback."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except ArmkitError as err:
            stderr.print(f"armkit: {err}", markup=False)
            raise typer.Exit(EXIT_BAD_INPUT) from None


app = typer.Typer(cls=_Group, no_args_is_help=True, add_completion=False,
                  pretty_exceptions_enable=False, rich_markup_mode=None,
                  help="Serial robot arms: models, kinematics, workspace, trajectories, "
                       "planning, calibration and Modbus TCP drives.")

JsonFlag = Annotated[bool, typer.Option("--json", help="Print one JSON document and nothing else.")]
SiFlag = Annotated[bool, typer.Option("--si", help="Numbers in m and rad, not the file's units.")]
# Lets "-30" stand as a joint value rather than an unknown option.
NUMBERS = {"ignore_unknown_options": True}


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def print_json(document: Any) -> None:
    """Write one JSON document to stdout (NumPy values converted)."""
    sys.stdout.write(json.dumps(document, default=_plain, allow_nan=True) + "\n")


def main() -> None:
    """Entry point of the `armkit` console script."""
    app()

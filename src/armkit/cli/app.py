"""The `armkit` command: one Typer app, library errors turned into one line and exit 2.

Exit status: 0 success, 1 a result that failed (unreachable target, no path), 2 bad input.
Every command that prints results takes ``--json``: one JSON document on stdout, nothing else.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from typer.core import TyperGroup

from armkit.errors import ArmkitError, DriveError, InputError

EXIT_FAILED, EXIT_BAD_INPUT = 1, 2

stdout = Console(highlight=False, soft_wrap=True)
stderr = Console(stderr=True, highlight=False, soft_wrap=True)


class _Group(TyperGroup):
    """Catches the library's errors once, at the edge: one stderr line and no traceback; exit 1
    for a drive that failed (a result), exit 2 for bad input."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except ArmkitError as err:
            stderr.print(f"armkit: {err}", markup=False)
            code = EXIT_FAILED if isinstance(err, DriveError) else EXIT_BAD_INPUT
            raise typer.Exit(code) from None


app = typer.Typer(cls=_Group, no_args_is_help=True, add_completion=False,
                  pretty_exceptions_enable=False, rich_markup_mode=None,
                  help="Serial robot arms: models, kinematics, workspace, trajectories, "
                       "planning, calibration and Modbus TCP drives.")

JsonFlag = Annotated[bool, typer.Option("--json", help="Print one JSON document and nothing else.")]
SiFlag = Annotated[bool, typer.Option("--si", help="Numbers in m and rad, not the file's units.")]
# Lets "-30" stand as a joint value rather than an unknown option.
NUMBERS = {"ignore_unknown_options": True}


def _plain(value: Any) -> Any:
    """The document with NumPy values as Python ones, and NaN and inf as null (not JSON)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def print_json(document: Any) -> None:
    """Write one JSON document to stdout: NumPy values converted, NaN and inf as null."""
    sys.stdout.write(json.dumps(_plain(document), allow_nan=False) + "\n")


def output_folder(path: Path, name: str = "--out") -> Path:
    """The folder figures go to, made if missing, before any work is done.

    Raises
    ------
    InputError
        ``--out: expected a folder armkit can write, found ...``.
    """
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"{name}: expected a folder armkit can write, found {path} "
                         f"({err.strerror or err})") from None
    return path


def main() -> None:
    """Entry point of the `armkit` console script."""
    app()

"""The `armkit` command: one Typer app, library errors turned into one line and exit 2.

Exit status: 0 success, 1 a result that failed (unreachable target, no path), 2 bad input.
Every command that prints results takes ``--json``: one JSON document on stdout, nothing else.
"""

from __future__ import annotations

import difflib
import importlib
import json
import math
import re
import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from typer.core import TyperGroup

from armkit.cli.values import label, output_path
from armkit.errors import ArmkitError, DriveError, InputError, cut
from armkit.io.documents import is_number

EXIT_FAILED, EXIT_BAD_INPUT = 1, 2
# What armkit does, as pyproject.toml's description says it.
DESCRIPTION = ("Serial robot arms: robot models (DH, modified DH, screws, URDF), forward and "
               "inverse kinematics, Jacobians, workspace, trajectories, collision-free path "
               "planning, hand-eye and kinematic calibration, targets in point clouds, joint "
               "waypoints to Modbus TCP drives, and the end-to-end job with its report.")

# Text from files and users (robot and joint names, file names, reasons) reaches the console as
# it is: no console markup ("[bold]" stays text; a stray "[/]" cannot raise) and no emoji codes
# (":x:" stays text). A command that styles its own words does so with rich.text.Text.
stdout = Console(highlight=False, soft_wrap=True, markup=False, emoji=False)
stderr = Console(stderr=True, highlight=False, soft_wrap=True, markup=False, emoji=False)


# Typer's usage errors (its own copy of click's): the classes come from typer's public one.
_UsageError = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "UsageError")


def _option_takes(command, ctx) -> dict[str, int]:
    """Each option name of `command` and how many values follow it (0 for a flag)."""
    takes = {name: 0 for name in command.get_help_option_names(ctx)}
    for param in command.params:
        if getattr(param, "param_type_name", "") == "option":
            for name in param.opts + param.secondary_opts:
                takes[name] = 0 if param.is_flag or param.count else param.nargs
    return takes


def _check_unknown_options(command, ctx, args: list[str]) -> None:
    """Refuse an unknown option where the command lets "-30" stand as a value, so that
    ``--bogus`` is an unknown option rather than a bad number."""
    if not command.context_settings.get("ignore_unknown_options"):
        return
    takes = _option_takes(command, ctx)
    i = 0
    while i < len(args):
        arg = args[i]
        if arg == "--":
            return
        name = arg.split("=", 1)[0]
        if name in takes:
            i += 1 + (0 if "=" in arg else takes[name])
            continue
        if arg.startswith("-") and len(arg) > 1 and not is_number(arg) \
                and arg[:2] not in takes:
            raise InputError(_unknown_option(name, _command_name(ctx), list(takes)))
        i += 1


def _command_name(ctx) -> str:
    """``armkit`` or ``armkit fk``, however the program was started (``python -m armkit``)."""
    if ctx is None or ctx.parent is None:
        return "armkit"
    return f"armkit {ctx.info_name}"


def _unknown_option(name: str, command: str, known: list[str]) -> str:
    known = sorted(set(known))
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean {close[0]}?" if close else ""
    return (f"{name}: expected an option of `{command}` ({', '.join(known)}), found an "
            f"unknown option{hint}")


def usage_line(err) -> str:
    """A usage error (typer's copy of click's) as one line naming the option or argument."""
    command = _command_name(getattr(err, "ctx", None))
    kind, param = type(err).__name__, getattr(err, "param", None)
    if kind == "NoSuchOption":
        known = list(err.possibilities or ())
        if err.ctx is not None:
            known = list(_option_takes(err.ctx.command, err.ctx))
        return _unknown_option(err.option_name, command, known)
    if kind == "MissingParameter" and param is not None:
        return f"{label(param)}: expected a value, found none (see `{command} --help`)"
    if param is not None:
        message = err.message
        if message.startswith("Value error, "):      # a parser's ValueError, via pydantic
            message = message.removeprefix("Value error, ")
        return f"{label(param)}: {message}"
    if getattr(err, "option_name", None):
        wanted = re.search(r"requires (\d+) arguments", err.message)
        if wanted:
            return f"{err.option_name}: expected {wanted[1]} values, found fewer"
        return f"{err.option_name}: {err.message}"
    unknown = re.match(r"No such command '([^']*)'", err.message)
    if unknown and getattr(err, "ctx", None) is not None:
        names = err.ctx.command.list_commands(err.ctx)
        close = difflib.get_close_matches(unknown[1], names, n=1)
        return (f"COMMAND: expected one of {', '.join(names)}, found {unknown[1]!r}"
                + (f"; did you mean {close[0]}?" if close else ""))
    extra = re.match(r"Got unexpected extra argument\S* \((.*)\)", err.message)
    if extra:
        return f"{command}: expected no more arguments, found {extra[1]!r}"
    return f"{command}: {err.message}"


LONGEST_MESSAGE = 1000
"""Characters of an error line at most: values are cut where messages are made (300
characters for a file's error); this bounds what no message should reach (a list of options)."""


def one_line(text: str) -> str:
    """A message on one line, however it came, short enough that ``armkit: `` and it make at
    most `LONGEST_MESSAGE` characters."""
    line = " ".join(part.strip() for part in str(text)[:100_000].splitlines() if part.strip())
    return cut(line, LONGEST_MESSAGE - len("armkit: "))


class _Group(TyperGroup):
    """Catches the library's errors and click's usage errors once, at the edge: one stderr
    line and no traceback; exit 1 for a drive that failed (a result), exit 2 for bad input."""

    def _report(self, run, *args):
        try:
            return run(*args)
        except _UsageError as err:
            if type(err).__name__ == "NoArgsIsHelpError":
                raise
            stderr.print(f"armkit: {one_line(usage_line(err))}", markup=False)
            raise typer.Exit(EXIT_BAD_INPUT) from None
        except ArmkitError as err:
            stderr.print(f"armkit: {one_line(err)}", markup=False)
            code = EXIT_FAILED if isinstance(err, DriveError) else EXIT_BAD_INPUT
            raise typer.Exit(code) from None

    def make_context(self, info_name, args, parent=None, **extra):
        return self._report(super().make_context, info_name, args, parent, **extra)

    def invoke(self, ctx):
        return self._report(super().invoke, ctx)

    def resolve_command(self, ctx, args):
        name, command, rest = super().resolve_command(ctx, args)
        if command is not None:
            _check_unknown_options(command, type(ctx)(command, info_name=name, parent=ctx),
                                   rest)
        return name, command, rest


app = typer.Typer(cls=_Group, no_args_is_help=True, add_completion=False,
                  pretty_exceptions_enable=False, rich_markup_mode=None,
                  help=DESCRIPTION)


@app.callback()
def _armkit() -> None:
    # A group even when one module's commands are loaded (`main`): Typer would run a lone
    # command as the whole program.
    pass


# The module of each command (`main` loads only the one a command line runs), and the modules
# in the order of `armkit --help`.
COMMAND_MODULES = {"handeye": "calibration", "calibrate": "calibration",
                   "accuracy": "calibration", "send": "drives", "sim-drive": "drives",
                   "ik": "ik", "run": "job", "demo": "job", "view": "job",
                   "detect": "perception", "plan": "plan", "robots": "robots", "show": "robots",
                   "fk": "robots", "traj": "trajectory", "warm-up": "warmup",
                   "workspace": "workspace", "dynamics": "dynamics", "reach": "reach",
                   "place": "reach"}
MODULES = tuple(dict.fromkeys(COMMAND_MODULES.values()))

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


def output_folder(path: Path, name: str = "--out", files: tuple[str, ...] = ()) -> Path:
    """The folder figures go to, made if missing, and the `files` a command will write in it,
    checked writable before any work is done (`armkit.cli.values.output_path`).

    Raises
    ------
    InputError
        ``--out: expected a folder armkit can write in, found 'out' (Read-only file system)``.
    """
    return output_path(path, name, folder=True, files=files)


def load_commands(modules: tuple[str, ...] = MODULES) -> None:
    """Register the commands of these modules of `armkit.cli` on `app` (importing them)."""
    for module in modules:
        importlib.import_module(f"armkit.cli.{module}")


def main() -> None:
    """Entry point of the `armkit` console script: the module of the command asked for is the
    only one loaded (every module for help or an unknown command), then the command runs."""
    asked = next((arg for arg in sys.argv[1:] if not arg.startswith("-")), None)
    module = COMMAND_MODULES.get(asked)
    load_commands((module,) if module else MODULES)
    app()

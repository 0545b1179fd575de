"""Numbers and robots at the command line's edge: one check for every value a user types.

Every number an `armkit` command takes goes through `check_number`, either as a parser
(`number`, for options and arguments that are single numbers) or through `parse_numbers` (for
lists typed as one string, ``--q0 "0 -90 90 0 0 0"`` or ``--start=0,-90,...``). A value that is
not a number, not finite, or outside the range that makes sense for it is refused before any
work, with one message naming the argument, what was expected and what was found.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import typer

from armkit.errors import ArmkitError, InputError
from armkit.io.documents import LARGEST

# Coordinates and joint values in file units (mm or m, deg or rad): 1e9 mm is 1000 km, far past
# any arm, and well inside the range where squares and sums of floats stay finite.
COORDINATE = LARGEST
# Limits typed by the user (velocity, acceleration, jerk), file units per s, s^2, s^3.
LIMIT = (1e-6, 1e9)
DURATION = (1e-6, 1e6)            # s: a microsecond to about eleven days
TIMEOUT = (1e-3, 3600.0)          # s: a network time-out
LONGEST_NAME = 255                # characters of a file name (NAME_MAX on Linux, macOS, NTFS)


def shown(value: Any) -> str:
    """A value as a message shows it: its repr, cut at 40 characters."""
    text = value if isinstance(value, str) else repr(value)
    text = repr(text) if isinstance(value, str) else text
    return text if len(text) <= 40 else text[:37] + "..."


def _bound(x: float) -> str:
    return f"{x:g}"


def check_number(name: str, value: Any, low: float = -COORDINATE, high: float = COORDINATE,
                 *, low_open: bool = False, integer: bool = False, unit: str = "") -> float:
    """`value` as a float (or int) within ``[low, high]`` (``(low, high]`` if `low_open`).

    Raises
    ------
    InputError
        ``--pose: expected a number from -1e+09 to 1e+09, found 1e+155``.
    """
    what = "a whole number" if integer else "a number"
    span = (f"above {_bound(low)} and at most {_bound(high)}" if low_open else
            f"from {_bound(low)} to {_bound(high)}") + (f" {unit}" if unit else "")
    try:
        x = float(str(value).replace("_", "")) if isinstance(value, str) else float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected {what} {span}, found {shown(value)}") from None
    if not math.isfinite(x):
        raise InputError(f"{name}: expected a finite number {span}, found {shown(value)}")
    if integer and x != math.floor(x):
        raise InputError(f"{name}: expected {what} {span}, found {shown(value)}")
    if x < low or x > high or (low_open and x == low):
        raise InputError(f"{name}: expected {what} {span}, found {x:g}")
    return int(x) if integer else x


def parse_numbers(name: str, text: str, count: int | None = None,
                  low: float = -COORDINATE, high: float = COORDINATE, **kwargs) -> list[float]:
    """Numbers typed as one string, separated by spaces or commas, each checked.

    Raises
    ------
    InputError
        If one is not a number in range, or there are not `count` of them.
    """
    values = [v for v in re.split(r"[\s,]+", text.strip()) if v]
    if count is not None and len(values) != count:
        raise InputError(f"{name}: expected {count} numbers separated by spaces or commas, "
                         f"found {len(values)} in {shown(text)}")
    if not values:
        raise InputError(f"{name}: expected numbers separated by spaces or commas, found none")
    return [check_number(name, v, low, high, **kwargs) for v in values]


def label(param: Any) -> str:
    """The name a user typed or read for a command-line parameter: ``--pose``, ``-n``, ``Q``."""
    if param is None:
        return "argument"
    if getattr(param, "param_type_name", "") == "option" and getattr(param, "opts", None):
        return max(param.opts, key=len)
    return str(param.name or "argument").upper()


def number(low: float = -COORDINATE, high: float = COORDINATE, *, low_open: bool = False,
           integer: bool = False, unit: str = ""):
    """A parser for ``typer.Option(parser=...)``/``typer.Argument``: one number checked by
    `check_number`; a bad one is a usage error that the `armkit` group prints as one line
    naming the option."""

    def parse(value: Any) -> float:
        try:
            return check_number("value", value, low, high, low_open=low_open, integer=integer,
                                unit=unit)
        except InputError as err:
            raise typer.BadParameter(str(err).split(": ", 1)[1]) from None

    return parse


def robot_text(name: str, text: str) -> str:
    """A robot argument (a built-in name or a file) that the file system can look up.

    Raises
    ------
    InputError
        If a part of the path is longer than a file name can be, or it holds a NUL.
    """
    longest = max((len(part) for part in re.split(r"[/\\]", text)), default=0)
    if longest > LONGEST_NAME:
        raise InputError(f"{name}: expected a built-in name or a robot file, found a name of "
                         f"{longest} characters (at most {LONGEST_NAME}): {shown(text)}")
    if "\0" in text:
        raise InputError(f"{name}: expected a built-in name or a robot file, found a NUL "
                         f"character in {shown(text)}")
    return text


def load_robot(text: str, name: str = "robot"):
    """`armkit.robot(text)` with a bad name or an unreadable file as one InputError."""
    import armkit

    robot_text(name, text)
    try:
        return armkit.robot(text)
    except ArmkitError:
        raise
    except OSError as err:
        raise InputError(f"{name}: expected a built-in name or a readable robot file, found "
                         f"{shown(text)} ({err.strerror or err})") from None


FIGURE_FORMATS = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".tif", ".tiff", ".eps",
                  ".ps")
"""File endings matplotlib writes figures in."""


def _out_error(name: str, path: Path, expected: str, found: str) -> InputError:
    return InputError(f"{name}: expected {expected}, found {shown(str(path))} ({found})")


def _probe(name: str, folder: Path) -> None:
    """Write and remove a file in `folder`: a folder that says it is writable may not be (a
    read-only mount, a full disk, another user's)."""
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".armkit-", suffix=".probe"):
            pass
    except OSError as err:
        raise _out_error(name, folder, "a folder armkit can write in",
                         err.strerror or type(err).__name__) from None


def output_path(path: Path | str, name: str = "--out", *, folder: bool,
                files: Iterable[str] = (), formats: Iterable[str] = ()) -> Path:
    """An output checked before any work: everything a command will write there can be written.

    Parameters
    ----------
    path : Path or str
        What the user gave.
    name : str
        The option, for the message.
    folder : bool
        A folder (made if missing, with its parents) that `files` go into; else one file, in a
        folder that exists.
    files : iterable of str
        The names the command will write in the folder (or beside the file: e.g. the
        figure of ``calibrate --out robot.yaml``, as paths relative to the file's folder).
    formats : iterable of str
        The endings the file may have (``.png``, ...); empty for any.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        One line naming the option, the path and what is wrong: not a folder, not writable, an
        existing folder where a file goes, an ending armkit does not write.
    """
    text = str(path)
    longest = max((len(part) for part in re.split(r"[/\\]", text)), default=0)
    if "\0" in text or not text.strip() or longest > LONGEST_NAME or len(text) > 4096:
        raise InputError(f"{name}: expected a path, found {shown(text)}")
    path = Path(text)
    formats = tuple(f.lower() for f in formats)
    if folder:
        if path.exists() and not path.is_dir():
            raise _out_error(name, path, "a folder", "a file of that name exists")
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise _out_error(name, path, "a folder armkit can write",
                             err.strerror or type(err).__name__) from None
        base = path
    else:
        if formats and path.suffix.lower() not in formats:
            raise _out_error(name, path, f"a file ending in {', '.join(formats)}",
                             f"the ending {path.suffix or 'none'!r}")
        base = path.parent if str(path.parent) else Path(".")
        if not base.is_dir():
            raise _out_error(name, path, "a file in an existing folder", f"no folder {base}")
        files = (path.name, *files)
    _probe(name, base)
    for file in files:
        target = base / file
        if target.is_dir():
            raise _out_error(name, target, "a file armkit can write", "a folder of that name "
                             "exists")
        if not target.parent.is_dir():
            raise _out_error(name, target, "a file in an existing folder",
                             f"no folder {target.parent}")
        if target.exists() and not (target.is_file() and os.access(target, os.W_OK)):
            raise _out_error(name, target, "a file armkit can write",
                             "not a regular file" if not target.is_file() else "read-only")
    return path

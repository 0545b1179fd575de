"""Numbers and robots at the command line's edge: one check for every value a user types.

Every number an `armkit` command takes goes through `check_number`, either as a parser
(`number`, for options and arguments that are single numbers) or through `parse_numbers` (for
lists typed as one string, ``--q0 "0 -90 90 0 0 0"`` or ``--start=0,-90,...``). A value that is
not a number, not finite, or outside the range that makes sense for it is refused before any
work, with one message naming the argument, what was expected and what was found.
"""

from __future__ import annotations

import math
import re
from typing import Any

import typer

from armkit.errors import ArmkitError, InputError

# Coordinates and joint values in file units (mm or m, deg or rad): 1e9 mm is 1000 km, far past
# any arm, and well inside the range where squares and sums of floats stay finite.
COORDINATE = 1e9
# Limits typed by the user (velocity, acceleration, jerk), file units per s, s^2, s^3.
LIMIT = (1e-6, 1e9)
DURATION = (1e-6, 1e6)            # s: a microsecond to about eleven days
TIMEOUT = (1e-3, 3600.0)          # s: a network time-out
LONGEST_NAME = 255                # characters of a file name (NAME_MAX on Linux, macOS, NTFS)


def _shown(value: Any) -> str:
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
        raise InputError(f"{name}: expected {what} {span}, found {_shown(value)}") from None
    if not math.isfinite(x):
        raise InputError(f"{name}: expected a finite number {span}, found {_shown(value)}")
    if integer and x != math.floor(x):
        raise InputError(f"{name}: expected {what} {span}, found {_shown(value)}")
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
                         f"found {len(values)} in {_shown(text)}")
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
                         f"{longest} characters (at most {LONGEST_NAME}): {_shown(text)}")
    if "\0" in text:
        raise InputError(f"{name}: expected a built-in name or a robot file, found a NUL "
                         f"character in {_shown(text)}")
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
                         f"{_shown(text)} ({err.strerror or err})") from None

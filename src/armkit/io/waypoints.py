"""Waypoint files: joint waypoints, one a row, in the robot file's units, and their times.

CSV: one waypoint a row; a header row names the joints and, optionally, a time column ``t``
(s). Without a header: n columns, or n + 1 with the time first. JSON: a list of rows as in
CSV, or ``{"q": [[...], ...], "t": [...]}``. Every mistake is one `ModelFileError` naming the
file, the line (CSV) or field (JSON), what was expected and what was found.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from armkit.errors import ModelFileError
from armkit.io.documents import check_number, number_from_text, read_text
from armkit.model import Robot

TIME_COLUMNS = ("t", "time")


def read_waypoints(path: Path, robot: Robot) -> tuple[np.ndarray, np.ndarray | None]:
    """Waypoints (N, n) and times (N,) or None from a CSV or JSON file, in the robot file's units.

    CSV: one waypoint a row; a header row names the joints and, optionally, a time column
    ``t`` (s). Without a header: n columns, or n + 1 with the time first. JSON: a list of rows
    as in CSV, or ``{"q": [[...], ...], "t": [...]}``.

    Raises
    ------
    ModelFileError
    """
    text = read_text(path)
    if Path(path).suffix.lower() == ".json":
        return _json_waypoints(text, str(path), robot)
    # (line number, row) of the rows that hold anything, so errors name the file's own lines.
    rows = [(line, row) for line, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and any(c.strip() for c in row)]
    if not rows:
        raise ModelFileError(str(path), "", "waypoints, one a row", "an empty file")
    header = None
    if not _numbers(rows[0][1]):
        header = [c.strip() for c in rows[0][1]]
        rows = rows[1:]
    columns = _columns(header, str(path), robot)
    q, t = [], []
    for line, row in rows:
        values = _numbers(row)
        width = len(columns) if header else len(row)
        if values is None or len(values) != width or (not header and width not in
                                                      (robot.n, robot.n + 1)):
            expected = (f"{len(columns)} numbers ({', '.join(header)})" if header else
                        f"{robot.n} numbers (the joints of {robot.name}), or {robot.n + 1} "
                        f"with the time first")
            raise ModelFileError(str(path), f"line {line}", expected,
                                 ", ".join(c.strip() for c in row))
        _finite(row, str(path), line)
        if header:
            q.append([values[columns.index(name)] for name in robot.joint_names])
            if "t" in columns:
                t.append(values[columns.index("t")])
        else:
            q.append(values[-robot.n:])
            if width == robot.n + 1:
                t.append(values[0])
    if not q:
        raise ModelFileError(str(path), "", "at least one waypoint", "a header only")
    return np.array(q), (np.array(t) if t else None)


def _numbers(row: list[str]) -> list[float] | None:
    """The row's numbers, or None if a cell is not a plain decimal (a header's names)."""
    try:
        return [float(c) if c.strip().lower().lstrip("+-") in ("nan", "inf", "infinity")
                else float(check_number(c, -math.inf, math.inf)) for c in row]
    except ValueError:
        return None


def _finite(row: list[str], path: str, line: int) -> None:
    """Every cell a finite number within the files' range (`check_number`)."""
    for column, cell in enumerate(row, start=1):
        number_from_text(cell, path, f"line {line}, column {column}")


def _columns(header: list[str] | None, path: str, robot: Robot) -> list[str]:
    if header is None:
        return []
    columns = ["t" if c.lower() in TIME_COLUMNS else c for c in header]
    missing = [name for name in robot.joint_names if name not in columns]
    unknown = [c for c in columns if c != "t" and c not in robot.joint_names]
    if missing or unknown or len(set(columns)) != len(columns):
        raise ModelFileError(path, "line 1", f"a header naming each joint of {robot.name} once "
                             f"({', '.join(robot.joint_names)}) and optionally t",
                             ", ".join(header))
    return columns


def _json_waypoints(text: str, path: str, robot: Robot):
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise ModelFileError(path, f"line {err.lineno}", "valid JSON", err.msg) from None
    if isinstance(doc, dict):
        unknown = set(doc) - {"q", "t"}
        if "q" not in doc or unknown:
            raise ModelFileError(path, "", 'fields "q" and optionally "t"',
                                 ", ".join(sorted(map(repr, unknown))) or "no \"q\"")
        q, t = doc["q"], doc.get("t")
    else:
        q, t = doc, None
    for name, values in (("q", q), ("t", t)):
        _json_numbers(values, path, name)
    try:
        q = np.array(q, dtype=float)
        t = None if t is None else np.array(t, dtype=float)
    except (TypeError, ValueError):
        raise ModelFileError(path, "q", "rows of numbers", "something else") from None
    except OverflowError:                  # an integer beyond float's range, 1e309 and up
        raise ModelFileError(path, "q", "numbers of a float's range", "an integer of more "
                             "than 308 digits") from None
    for name, values in (("q", q), ("t", t)):
        if values is not None and not np.isfinite(values).all():
            where = np.argwhere(~np.isfinite(values))[0]
            raise ModelFileError(path, f"{name}{''.join(f'[{i}]' for i in where)}",
                                 "finite numbers", str(values[tuple(where)]))
    if q.ndim != 2 or q.shape[1] not in (robot.n, robot.n + 1) or len(q) == 0:
        raise ModelFileError(path, "q", f"rows of {robot.n} numbers (the joints of "
                             f"{robot.name}), or {robot.n + 1} with the time first",
                             f"shape {q.shape}")
    if q.shape[1] == robot.n + 1:
        if t is not None:
            raise ModelFileError(path, "t", "times in one place: a first column or \"t\"",
                                 "both")
        q, t = q[:, 1:], q[:, 0]
    return q, t


def _json_numbers(values, path: str, name: str, depth: int = 0) -> None:
    """Every leaf of (nested lists of) `values` a number by `check_number` (true, "1" and
    1e400 are not)."""
    if values is None and depth == 0:
        return
    if isinstance(values, list) and depth < 2:
        for i, value in enumerate(values):
            _json_numbers(value, path, f"{name}[{i}]", depth + 1)
        return
    try:
        if isinstance(values, str):            # "1" in JSON is text, not a number
            raise ValueError(f"expected a number, found {values[:40]!r}")
        check_number(values)
    except ValueError as err:
        expected, _, found = str(err).removeprefix("expected ").partition(", found ")
        raise ModelFileError(path, name, expected, found) from None

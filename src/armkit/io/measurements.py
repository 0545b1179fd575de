"""Measurement files (CSV): calibration measurements, candidate pools, accuracy experiments.

Comment lines start with ``#``; one of them may declare the units, ``# units: mm deg`` (length,
then angle). The first other line is the header.

Calibration measurements: the joint values (columns named as the robot's joints, or q1 .. qn),
then the measured tool position ``x, y, z`` and optionally its orientation ``roll, pitch, yaw``
(``Rz(yaw) Ry(pitch) Rx(roll)``); units default to the robot file's::

    # units: mm deg
    lift,swing1,swing2,swing3,x,y,z
    100,10,-20,30,1290.1,250.3,625.4

A pool of candidate configurations is the same with the joint columns alone.

Accuracy experiments: commanded then measured positions; the units line is required::

    # units: mm
    commanded_x,commanded_y,commanded_z,measured_x,measured_y,measured_z
    200,300,500,202,296,503
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armkit.errors import ModelFileError
from armkit.io.documents import number_from_text, read_text
from armkit.model.robot import Robot, Units
from armkit.spatial import rpy_to_matrix

ACCURACY_COLUMNS = ("commanded_x", "commanded_y", "commanded_z",
                    "measured_x", "measured_y", "measured_z")


@dataclass(frozen=True)
class Table:
    """A CSV file's header, numeric rows (k, columns), declared length and angle units (None
    where the file declares none), and each row's line number."""

    path: str
    header: tuple[str, ...]
    values: np.ndarray
    length: str | None
    angle: str | None
    lines: tuple[int, ...]

    def units(self, default: Units) -> Units:
        """The declared units, the missing ones taken from `default`."""
        return Units(self.length or default.length, self.angle or default.angle)


def read_table(path: str | Path) -> Table:
    """A numeric CSV file with ``#`` comments and an optional ``# units: LENGTH [ANGLE]`` line.

    Raises
    ------
    ModelFileError
        Naming the file and line: a bad units line, no header, a row of another length, a
        value that is not a finite number, no rows.
    """
    path = str(path)
    text = read_text(path)
    units, header, rows, lines = (None, None), None, [], []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            body = stripped.lstrip("#").strip()
            if body.lower().startswith("units:"):
                if units != (None, None) or header is not None:
                    raise ModelFileError(path, f"line {number}", "one units line, before the "
                                         "header", "another" if header is None
                                         else "one after the header")
                units = _units(body.split(":", 1)[1].split(), path, number)
            continue
        cells = [c.strip() for c in next(csv.reader([stripped]))]
        if header is None:
            header = tuple(cells)
            if len(set(header)) != len(header):
                twice = next(c for c in header if header.count(c) > 1)
                raise ModelFileError(path, f"line {number}", "distinct column names",
                                     f"{twice!r} twice")
            continue
        if len(cells) != len(header):
            raise ModelFileError(path, f"line {number}", f"{len(header)} values (one per "
                                 f"column of the header)", f"{len(cells)}")
        rows.append([number_from_text(cell, path, f"line {number}, column {name[:40]}")
                     for name, cell in zip(header, cells)])
        lines.append(number)
    if header is None:
        raise ModelFileError(path, "", "a header line naming the columns", "none")
    if not rows:
        raise ModelFileError(path, "", "at least one row of values under the header", "none")
    return Table(path, header, np.array(rows, dtype=float), *units, tuple(lines))


def _units(words: list[str], path: str, number: int) -> tuple[str, str | None]:
    length = words[0] if words else None
    angle = words[1] if len(words) > 1 else None
    if length not in ("m", "mm") or angle not in ("rad", "deg", None) or len(words) > 2:
        raise ModelFileError(path, f"line {number}", "units as 'LENGTH [ANGLE]' with LENGTH "
                             "m or mm and ANGLE rad or deg", repr(" ".join(words)))
    return length, angle


def _joint_columns(table: Table, robot: Robot) -> list[int]:
    """Indices of the robot's joint columns: its joint names, or q1 .. qn."""
    for names in (robot.joint_names, tuple(f"q{i + 1}" for i in range(robot.n))):
        if all(n in table.header for n in names):
            return [table.header.index(n) for n in names]
    raise ModelFileError(table.path, "header", f"the joints of {robot.name} as columns "
                         f"({', '.join(robot.joint_names)} or q1 .. q{robot.n})",
                         ", ".join(table.header))


def _joint_values(table: Table, robot: Robot, units: Units) -> np.ndarray:
    q = table.values[:, _joint_columns(table, robot)]
    return np.where(robot.chain.revolute, units.angle_to_si(q), units.length_to_si(q))


@dataclass(frozen=True)
class Measurements:
    """Calibration measurements in SI: joint values (m, n) and positions (m, 3) or poses
    (m, 4, 4); the units the file spoke in; each row's line number."""

    q: np.ndarray
    measured: np.ndarray
    units: Units
    lines: tuple[int, ...]


def read_measurements(path: str | Path, robot: Robot) -> Measurements:
    """Read a calibration measurements file for `robot` (see the module's docstring).

    Raises
    ------
    ModelFileError
    """
    table = read_table(path)
    units = table.units(robot.units)
    q = _joint_values(table, robot, units)
    missing = [c for c in ("x", "y", "z") if c not in table.header]
    if missing:
        raise ModelFileError(table.path, "header", "measured position columns x, y, z",
                             f"no {', '.join(missing)} in {', '.join(table.header)}")
    rpy_names = ("roll", "pitch", "yaw")
    has_rpy = [c in table.header for c in rpy_names]
    if any(has_rpy) and not all(has_rpy):
        raise ModelFileError(table.path, "header", "all of roll, pitch, yaw or none of them",
                             ", ".join(c for c, h in zip(rpy_names, has_rpy) if h))
    known = set(_joint_columns(table, robot)) | {table.header.index(c) for c in "xyz"}
    if all(has_rpy):
        known |= {table.header.index(c) for c in rpy_names}
    extra = [table.header[i] for i in range(len(table.header)) if i not in known]
    if extra:
        raise ModelFileError(table.path, "header", "joint columns, x, y, z and optionally "
                             "roll, pitch, yaw", f"unknown column {extra[0]!r}")
    p = units.length_to_si(table.values[:, [table.header.index(c) for c in "xyz"]])
    if all(has_rpy):
        rpy = units.angle_to_si(table.values[:, [table.header.index(c) for c in rpy_names]])
        measured = np.zeros((len(p), 4, 4))
        measured[:, :3, :3] = rpy_to_matrix(rpy)
        measured[:, :3, 3] = p
        measured[:, 3, 3] = 1.0
    else:
        measured = p
    return Measurements(q, measured, units, table.lines)


def read_pool(path: str | Path, robot: Robot) -> np.ndarray:
    """Candidate configurations (k, n) in SI from a CSV with the robot's joint columns (other
    columns, such as x, y, z, are ignored); units default to the robot file's.

    Raises
    ------
    ModelFileError
    """
    table = read_table(path)
    return _joint_values(table, robot, table.units(robot.units))


@dataclass(frozen=True)
class AccuracyData:
    """Commanded and measured positions (m, 3) in SI, and the units the file spoke in."""

    commanded: np.ndarray
    measured: np.ndarray
    units: Units


def read_accuracy(path: str | Path) -> AccuracyData:
    """Read an accuracy experiment (see the module's docstring).

    Raises
    ------
    ModelFileError
    """
    table = read_table(path)
    if table.length is None:
        raise ModelFileError(table.path, "units", "a '# units: mm' (or m) line before the "
                             "header", "none")
    units = table.units(Units())
    if set(table.header) != set(ACCURACY_COLUMNS):
        raise ModelFileError(table.path, "header", f"the columns {', '.join(ACCURACY_COLUMNS)}",
                             ", ".join(table.header))
    v = units.length_to_si(table.values[:, [table.header.index(c) for c in ACCURACY_COLUMNS]])
    return AccuracyData(v[:, :3], v[:, 3:], units)

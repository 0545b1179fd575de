"""Robot files (YAML) to validated robots, and back; the built-in robots.

A robot file declares its units and convention, then its joints in those units::

    name: water_supply
    units: {length: mm, angle: deg}
    convention: mdh            # dh | mdh | poe | urdf
    base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}    # optional
    tool: {xyz: [0, 0, 0], rpy: [0, 0, 0]}    # optional
    joints:
      - {name: lift, type: prismatic, alpha: 0, a: 0, d: 0, theta: 0, limits: [0, 600]}

DH rows take ``alpha a d theta``; screw rows (``poe``) take ``axis`` and ``point`` and the file a
``home`` pose; a ``urdf`` file names ``urdf: path`` (relative to the file) and optionally ``tip``.
Every mistake raises one `ModelFileError` naming the file, the field, what was expected and
what was found.
"""

from __future__ import annotations

import difflib
import math
import os
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import Field, ValidationError, field_validator, model_validator

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import StrictModel, found_text, read_yaml, validation_error
from armkit.model.chain import Limits
from armkit.model.collision import CollisionShape, CollisionSpec
from armkit.model.dh import DHRow, DHTable, chain_from_dh
from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
from armkit.model.robot import Robot, Units
from armkit.model.urdf import URDFTable, chain_from_urdf, read_urdf
from armkit.spatial import matrix_to_rpy, pose_from_xyz_rpy

Vector3 = Annotated[list[float], Field(min_length=3, max_length=3)]


class PoseField(StrictModel):
    xyz: Vector3 = [0.0, 0.0, 0.0]
    rpy: Vector3 = [0.0, 0.0, 0.0]


class UnitsField(StrictModel):
    length: Literal["mm", "m"]
    angle: Literal["deg", "rad"]


class _JointField(StrictModel):
    name: str | None = None
    limits: list[float] | None = None
    velocity: float | None = Field(None, gt=0)
    acceleration: float | None = Field(None, gt=0)

    @field_validator("limits")
    @classmethod
    def _ordered(cls, v):
        if v is not None and (len(v) != 2 or not v[0] < v[1]):
            raise ValueError(f"expected [lower, upper] with lower < upper, found {v}")
        return v


class DHJointField(_JointField):
    type: Literal["revolute", "prismatic", "fixed"]
    alpha: float
    a: float
    d: float
    theta: float

    @model_validator(mode="after")
    def _limits_match_type(self):
        if self.type == "prismatic" and self.limits is None:
            raise ValueError("expected limits [lower, upper] for a prismatic joint, found none")
        if self.type == "fixed" and (self.limits or self.velocity or self.acceleration):
            raise ValueError("expected no limits on a fixed row, found some")
        return self


class ScrewJointField(_JointField):
    type: Literal["revolute", "prismatic"]
    axis: Vector3
    point: Vector3 | None = None

    @model_validator(mode="after")
    def _complete(self):
        if math.hypot(*self.axis) < 1e-9:
            raise ValueError(f"expected a non-zero axis, found {self.axis}")
        if self.type == "revolute" and self.point is None:
            raise ValueError("expected a point on the axis of a revolute joint, found none")
        if self.type == "prismatic" and self.limits is None:
            raise ValueError("expected limits [lower, upper] for a prismatic joint, found none")
        return self


class CollisionShapeField(StrictModel):
    link: int = Field(ge=0)
    a: Vector3
    b: Vector3 | None = None
    radius: float = Field(gt=0)


class CollisionField(StrictModel):
    """The optional ``collision:`` section (see `armkit.model.collision`), file length unit."""

    radius: float | None = Field(None, gt=0)
    shapes: list[CollisionShapeField] = []
    skip: list[Annotated[list[int], Field(min_length=2, max_length=2)]] = []

    @model_validator(mode="after")
    def _one_kind(self):
        if self.radius is not None and self.shapes:
            raise ValueError("expected either radius (default capsules) or shapes, found both")
        return self


class _RobotField(StrictModel):
    name: str
    description: str = ""
    units: UnitsField
    convention: Literal["dh", "mdh", "poe", "urdf"]
    base: PoseField | None = None
    tool: PoseField | None = None
    collision: CollisionField | None = None


class DHFile(_RobotField):
    joints: list[DHJointField] = Field(min_length=1)


class ScrewFile(_RobotField):
    home: PoseField
    joints: list[ScrewJointField] = Field(min_length=1)


class URDFFile(_RobotField):
    urdf: str
    tip: str | None = None


FILE_MODELS = {"dh": DHFile, "mdh": DHFile, "poe": ScrewFile, "urdf": URDFFile}


# --- reading ---------------------------------------------------------------------------------

def parse_robot(document: Any, path: str = "<robot>") -> Robot:
    """A Robot from a parsed robot document (a mapping, file units); `path` names it in errors.

    Raises
    ------
    ModelFileError
    """
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping of fields (name, units, convention, ...)",
                             type(document).__name__)
    convention = document.get("convention")
    if convention not in FILE_MODELS:
        raise ModelFileError(path, "convention", "one of dh, mdh, poe, urdf",
                             found_text(convention) if "convention" in document else "nothing")
    model = FILE_MODELS[convention]
    try:
        spec = model.model_validate(document)
    except ValidationError as err:
        raise validation_error(path, err, model) from None
    units = Units(spec.units.length, spec.units.angle)
    T_base, T_tool = _pose(spec.base, units), _pose(spec.tool, units)
    if isinstance(spec, URDFFile):
        found = read_urdf(Path(path).parent / spec.urdf, spec.tip)
        table = URDFTable(found.path, found.tip, found.joints, T_base, T_tool)
        chain = chain_from_urdf(table)
    elif isinstance(spec, ScrewFile):
        rows = tuple(_screw_row(j, i, units) for i, j in enumerate(spec.joints))
        table = ScrewTable(rows, _pose(spec.home, units), T_base, T_tool)
        chain = chain_from_poe(table)
    else:
        rows = tuple(_dh_row(j, units) for j in spec.joints)
        if all(r.kind == "fixed" for r in rows):
            raise ModelFileError(path, "joints", "at least one revolute or prismatic joint",
                                 "only fixed rows")
        table = DHTable(rows, convention == "mdh", T_base, T_tool)
        chain = chain_from_dh(table)
    collision = _collision(spec.collision, units, chain.n, path)
    return Robot(spec.name, chain, units, spec.description, table, collision)


def _collision(field: CollisionField | None, units: Units, n: int,
               path: str) -> CollisionSpec | None:
    """The collision section in SI; links are numbered 0 (base) to n (the last link)."""
    if field is None:
        return None
    for i, s in enumerate(field.shapes):
        if s.link > n:
            raise ModelFileError(path, f"collision.shapes[{i}].link", f"a link 0 .. {n}",
                                 str(s.link))
    for i, pair in enumerate(field.skip):
        if not all(0 <= k <= n for k in pair):
            raise ModelFileError(path, f"collision.skip[{i}]", f"two links 0 .. {n}", str(pair))
    length = units.length_to_si
    shapes = tuple(CollisionShape(s.link, length(s.a), length(s.a if s.b is None else s.b),
                                  float(length(s.radius))) for s in field.shapes)
    radius = None if field.radius is None else float(length(field.radius))
    return CollisionSpec(radius, shapes, tuple((int(i), int(j)) for i, j in field.skip))


def _pose(pose: PoseField | None, units: Units) -> np.ndarray:
    if pose is None:
        return np.eye(4)
    return pose_from_xyz_rpy(units.length_to_si(pose.xyz), units.angle_to_si(pose.rpy))


def _limits(joint: _JointField, kind: str, units: Units) -> Limits | None:
    if kind == "fixed":
        return None
    to_si = units.angle_to_si if kind == "revolute" else units.length_to_si
    lower, upper = joint.limits if joint.limits is not None else (-math.pi, math.pi)
    if joint.limits is not None:
        lower, upper = float(to_si(lower)), float(to_si(upper))
    velocity, acceleration = (np.inf if v is None else float(to_si(v))
                              for v in (joint.velocity, joint.acceleration))
    return Limits(lower, upper, velocity, acceleration)


def _dh_row(joint: DHJointField, units: Units) -> DHRow:
    """A file row in SI; an unnamed row stays unnamed (the chain numbers moving joints)."""
    return DHRow(joint.type, float(units.angle_to_si(joint.alpha)),
                 float(units.length_to_si(joint.a)), float(units.length_to_si(joint.d)),
                 float(units.angle_to_si(joint.theta)), joint.name or "",
                 _limits(joint, joint.type, units))


def _screw_row(joint: ScrewJointField, i: int, units: Units) -> ScrewRow:
    point = None if joint.point is None else units.length_to_si(joint.point)
    return ScrewRow(joint.type, np.asarray(joint.axis, dtype=float),
                    _limits(joint, joint.type, units), point, joint.name or f"q{i + 1}")


def load_robot(path: str | Path) -> Robot:
    """Load a robot from a YAML robot file or a URDF file (.urdf: SI units).

    Raises
    ------
    ModelFileError
    """
    path = Path(path)
    if path.suffix.lower() == ".urdf":
        table = read_urdf(path)
        return Robot(path.stem, chain_from_urdf(table), Units("m", "rad"), "", table)
    return parse_robot(read_yaml(path), str(path))


# --- writing ---------------------------------------------------------------------------------

def _num(x: float) -> float:
    """A file value without the last-bit noise of the unit conversion (15 significant digits:
    525.5000000000001 is written 525.5, and nothing a double holds of a file value is lost)."""
    return float(f"{float(x):.15g}")


def _nums(xs) -> list[float]:
    return [_num(x) for x in np.asarray(xs, dtype=float).ravel()]


def _pose_doc(T: np.ndarray, units: Units) -> dict:
    return {"xyz": _nums(units.length_from_si(T[:3, 3])),
            "rpy": _nums(units.angle_from_si(matrix_to_rpy(T[:3, :3])))}


def _limits_doc(limits: Limits | None, kind: str, units: Units) -> dict:
    if limits is None or not np.isfinite(limits.lower):
        return {}
    from_si = units.angle_from_si if kind == "revolute" else units.length_from_si
    doc = {"limits": _nums(from_si([limits.lower, limits.upper]))}
    for key in ("velocity", "acceleration"):
        value = getattr(limits, key)
        if np.isfinite(value):
            doc[key] = _num(from_si(value))
    return doc


def robot_document(robot: Robot, folder: str | Path | None = None) -> dict:
    """The robot as a robot-file document (a dict in the robot's units), ready for YAML.

    ``folder``: where the document will be written; a URDF path is then given relative to it.

    Raises
    ------
    InputError
        If the robot was not built from a table (DH, screws or URDF).
    """
    u, table = robot.units, robot.table
    doc: dict[str, Any] = {"name": robot.name}
    if robot.description:
        doc["description"] = robot.description
    doc["units"] = {"length": u.length, "angle": u.angle}
    if isinstance(table, DHTable):
        doc["convention"] = "mdh" if table.modified else "dh"
    elif isinstance(table, ScrewTable):
        doc["convention"] = "poe"
    elif isinstance(table, URDFTable):
        urdf = table.path if folder is None else os.path.relpath(table.path, folder)
        doc.update(convention="urdf", urdf=urdf, tip=table.tip)
    else:
        raise InputError(f"robot {robot.name}: expected one built from a DH, screw or URDF "
                         f"table, found table {type(table).__name__}")
    for key, T in (("base", table.T_base), ("tool", table.T_tool)):
        if not np.allclose(T, np.eye(4), atol=1e-15):
            doc[key] = _pose_doc(T, u)
    if isinstance(table, DHTable):
        doc["joints"] = [{**({"name": r.name} if r.name else {}), "type": r.kind,
                          "alpha": _num(u.angle_from_si(r.alpha)),
                          "a": _num(u.length_from_si(r.a)), "d": _num(u.length_from_si(r.d)),
                          "theta": _num(u.angle_from_si(r.theta)),
                          **_limits_doc(r.limits, r.kind, u)} for r in table.rows]
    elif isinstance(table, ScrewTable):
        doc["home"] = _pose_doc(table.T_home, u)
        doc["joints"] = [{"name": r.name, "type": r.kind, "axis": _nums(r.axis),
                          **({} if r.point is None else
                             {"point": _nums(u.length_from_si(r.point))}),
                          **_limits_doc(r.limits, r.kind, u)} for r in table.rows]
    if robot.collision is not None:
        doc["collision"] = _collision_doc(robot.collision, u)
    return doc


def _collision_doc(spec: CollisionSpec, u: Units) -> dict:
    doc: dict[str, Any] = {}
    if spec.radius is not None:
        doc["radius"] = _num(u.length_from_si(spec.radius))
    if spec.shapes:
        doc["shapes"] = [{"link": s.link, "a": _nums(u.length_from_si(s.a)),
                          **({} if np.array_equal(s.a, s.b) else
                             {"b": _nums(u.length_from_si(s.b))}),
                          "radius": _num(u.length_from_si(s.radius))} for s in spec.shapes]
    if spec.skip:
        doc["skip"] = [list(p) for p in spec.skip]
    return doc


def save_robot(robot: Robot, path: str | Path) -> None:
    """Write the robot as a YAML robot file that `load_robot` reads back to the same robot."""
    text = yaml.safe_dump(robot_document(robot, Path(path).parent), sort_keys=False,
                          default_flow_style=None)
    Path(path).write_text(text, encoding="utf-8")


# --- built-in robots -------------------------------------------------------------------------

def _builtin_dir():
    return resources.files("armkit.model") / "robots"


def robots() -> list[str]:
    """Names of the built-in robots, sorted."""
    return sorted(p.name.removesuffix(".yaml") for p in _builtin_dir().iterdir()
                  if p.name.endswith(".yaml"))


def robot(name_or_path: str | Path | Robot) -> Robot:
    """A robot from a built-in name, a YAML robot file or a URDF file.

    Example
    -------
    >>> armkit.robot("ur5").n
    6

    Raises
    ------
    ModelFileError
        If the file is invalid.
    InputError
        If the name is neither built in nor an existing file.
    """
    if isinstance(name_or_path, Robot):
        return name_or_path
    text = str(name_or_path)
    if text in robots():
        with resources.as_file(_builtin_dir() / f"{text}.yaml") as path:
            return load_robot(path)
    if Path(text).is_file():
        return load_robot(text)
    hint = difflib.get_close_matches(text, robots(), n=1)
    raise InputError(f"robot: expected a built-in name ({', '.join(robots())}) or a robot file, "
                     f"found {text!r}" + (f" (did you mean {hint[0]!r}?)" if hint else ""))

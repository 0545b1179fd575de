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

import dataclasses
import difflib
import math
import os
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import Field, field_validator, model_validator

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import (Number, StrictModel, UnitsField, checked_path, found_text,
                                 kind_of, read_yaml, validated)
from armkit.model.chain import JERK_PER_ACCELERATION, Chain, Limits
from armkit.model.collision import CollisionShape, CollisionSpec
from armkit.model.dh import DHRow, DHTable, chain_from_dh
from armkit.model.inertia import Inertia, InertialModel, home_link_frames
from armkit.model.poe import ScrewRow, ScrewTable, chain_from_poe
from armkit.model.robot import Robot, Units
from armkit.io.srdf import read_srdf
from armkit.io.urdf import read_urdf
from armkit.model.urdf import URDFTable, chain_from_urdf, inertia_from_urdf
from armkit.spatial import invert, matrix_to_rpy, pose_from_xyz_rpy

Vector3 = Annotated[list[Number], Field(min_length=3, max_length=3)]

MAX_ROBOT_FILE_BYTES = 2**20
"""The largest robot file read (bytes); the built-in ones are about 1 kB."""

MAX_LENGTH = 1e3
"""The largest length a robot file may hold (m): no arm is a kilometre long, and a value such
as 1e308 would overflow the kinematics that follow."""

MAX_ANGLE = 1e3
"""The largest angle a robot file may hold (rad), about 160 turns."""

MAX_RATE = 1e6
"""The largest velocity or acceleration limit a robot file may hold (SI units)."""

MAX_AXIS = 1e3
"""The largest component of a screw axis direction (it is normalised)."""

MAX_MASS = 1e6
"""The largest mass a robot file may hold (kg)."""

MAX_INERTIA = 1e6
"""The largest inertia tensor entry a robot file may hold (kg m^2)."""

MAX_TORQUE = 1e7
"""The largest torque limit, friction or armature a robot file may hold (SI units)."""


class PoseField(StrictModel):
    xyz: Vector3 = [0.0, 0.0, 0.0]
    rpy: Vector3 = [0.0, 0.0, 0.0]


class _JointField(StrictModel):
    name: str | None = None
    limits: list[Number] | None = None
    velocity: Annotated[Number, Field(gt=0)] | None = None
    acceleration: Annotated[Number, Field(gt=0)] | None = None
    # Dynamics, SI whatever the file's units: N m (N), N m s/rad (N s/m), kg m^2 (kg).
    torque: Annotated[Number, Field(gt=0)] | None = None
    viscous: Annotated[Number, Field(ge=0)] | None = None
    coulomb: Annotated[Number, Field(ge=0)] | None = None
    armature: Annotated[Number, Field(ge=0)] | None = None
    jerk: Annotated[Number, Field(gt=0)] | None = None

    @field_validator("limits")
    @classmethod
    def _ordered(cls, v):
        if v is not None and (len(v) != 2 or not v[0] < v[1]):
            raise ValueError(f"expected [lower, upper] with lower < upper, found {found_text(v)}")
        return v


class DHJointField(_JointField):
    type: Literal["revolute", "prismatic", "fixed"]
    alpha: Number
    a: Number
    d: Number
    theta: Number

    @model_validator(mode="after")
    def _limits_match_type(self):
        if self.type == "prismatic" and self.limits is None:
            raise ValueError("expected limits [lower, upper] for a prismatic joint, found none")
        if self.type == "fixed" and any(getattr(self, key) is not None for key in JOINT_ONLY):
            raise ValueError(f"expected none of {', '.join(JOINT_ONLY)} on a fixed row, found "
                             f"some")
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


JOINT_ONLY = ("limits", "velocity", "acceleration", "jerk", "torque", "viscous", "coulomb",
              "armature")
"""The fields of a moving joint that a fixed DH row may not have."""

FRICTION_FIELDS = ("armature", "viscous", "coulomb")
"""A joint's dynamic fields that belong to the inertial model (`InertialModel`)."""


class BodyField(StrictModel):
    """A rigid body: kg, the file's length unit (com) and kg times its square (inertia, about
    the centre of mass: ixx iyy izz ixy ixz iyz)."""

    mass: Annotated[Number, Field(ge=0)]
    com: Vector3 = [0.0, 0.0, 0.0]
    inertia: Annotated[list[Number], Field(min_length=6, max_length=6)] = [0.0] * 6


class InertiaField(StrictModel):
    """The optional ``inertia:`` section: one body per moving joint (link frames; the base
    frame at home for screws), a payload in the tool frame, gravity (length unit / s^2)."""

    links: list[BodyField] | None = None
    payload: BodyField | None = None
    gravity: Vector3 | None = None


class CollisionShapeField(StrictModel):
    link: Annotated[int, Field(ge=0)] | str       # a link number, or a URDF robot's link name
    a: Vector3
    b: Vector3 | None = None
    radius: float = Field(gt=0)


class CollisionField(StrictModel):
    """The optional ``collision:`` section (see `armkit.model.collision`), file length unit."""

    radius: float | None = Field(None, gt=0)
    shapes: list[CollisionShapeField] = []
    # Link pairs never tested: by number, or by a URDF robot's link names.
    skip: list[Annotated[list[int], Field(min_length=2, max_length=2)]
               | Annotated[list[str], Field(min_length=2, max_length=2)]] = []
    adjacent: bool = False      # test adjacent links too (MoveIt's rule with an SRDF)

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
    inertia: InertiaField | None = None


class DHFile(_RobotField):
    joints: list[DHJointField] = Field(min_length=1)


class ScrewFile(_RobotField):
    home: PoseField
    joints: list[ScrewJointField] = Field(min_length=1)


class URDFFile(_RobotField):
    urdf: str
    tip: str | None = None
    srdf: str | None = None     # its disable_collisions pairs are left out of the checks


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
                             kind_of(document))
    convention = document.get("convention")
    if not isinstance(convention, str) or convention not in FILE_MODELS:
        raise ModelFileError(path, "convention", "one of dh, mdh, poe, urdf",
                             found_text(convention) if "convention" in document else "nothing")
    model = FILE_MODELS[convention]
    spec = validated(path, document, model)
    units = Units(spec.units.length, spec.units.angle)
    _check_magnitudes(spec, units, path)
    _check_unique_names(spec, path)
    T_base, T_tool = _pose(spec.base, units), _pose(spec.tool, units)
    if isinstance(spec, URDFFile):
        urdf = Path(path).parent / spec.urdf
        if not urdf.is_file():
            raise ModelFileError(path, "urdf", "a URDF file (its path relative to this file)",
                                 f"{found_text(spec.urdf)}, which is not a file")
        found = read_urdf(urdf, spec.tip)
        table = dataclasses.replace(found, T_base=T_base, T_tool=T_tool)
        chain = chain_from_urdf(table)
        inertia = inertia_from_urdf(table, chain)
        if spec.srdf is not None:
            srdf = Path(path).parent / spec.srdf
            if not srdf.is_file():
                raise ModelFileError(path, "srdf", "an SRDF file (its path relative to this "
                                     "file)", f"{found_text(spec.srdf)}, which is not a file")
            disabled = read_srdf(srdf, _srdf_links(table)).disabled_pairs
    elif isinstance(spec, ScrewFile):
        rows = tuple(_screw_row(j, i, units) for i, j in enumerate(spec.joints))
        table = ScrewTable(rows, _pose(spec.home, units), T_base, T_tool)
        chain = chain_from_poe(table)
        inertia = None
    else:
        rows = tuple(_dh_row(j, units) for j in spec.joints)
        if all(r.kind == "fixed" for r in rows):
            raise ModelFileError(path, "joints", "at least one revolute or prismatic joint",
                                 "only fixed rows")
        table = DHTable(rows, convention == "mdh", T_base, T_tool)
        chain = chain_from_dh(table)
        inertia = None
    names = _urdf_links(table) if isinstance(table, URDFTable) else {}
    collision = _collision(spec.collision, units, chain.n, path, names)
    if isinstance(spec, URDFFile) and spec.srdf is not None:
        collision = dataclasses.replace(collision or CollisionSpec(), adjacent=True,
                                        disabled=(collision.disabled if collision else ())
                                        + disabled)
    inertia = _inertia(spec, inertia, chain, units, path)
    return Robot(spec.name, chain, units, spec.description, table, collision, inertia)


def _urdf_links(table: URDFTable) -> dict[str, int]:
    """The URDF's link names on the arm (the chain's links and those merged into them), each
    with its link number."""
    names = {table.joints[0].parent: 0} if table.joints else {}
    moving = 0
    for joint in table.joints:
        moving += joint.kind != "fixed"
        names.setdefault(joint.child, moving)
    for c in table.collisions:
        names.setdefault(c.link, c.chain_link)
    return names


def _srdf_links(table: URDFTable) -> set[str]:
    """The link names an SRDF's pairs may give: the arm's, and those with collision elements
    that joints off the chain move (a gripper's fingers)."""
    return set(_urdf_links(table)) | set(table.detached)


def _collision(field: CollisionField | None, units: Units, n: int, path: str,
               names: dict[str, int]) -> CollisionSpec | None:
    """The collision section in SI; links are numbered 0 (base) to n (the last link), or
    named by a URDF robot's link names (`names`: name -> number)."""
    if field is None:
        return None
    shapes = []
    length = units.length_to_si
    for i, s in enumerate(field.shapes):
        if isinstance(s.link, str) and s.link not in names:
            raise ModelFileError(path, f"collision.shapes[{i}].link", "a link number or a "
                                 "link name of the URDF's arm", found_text(s.link))
        link = names[s.link] if isinstance(s.link, str) else s.link
        if link > n:
            raise ModelFileError(path, f"collision.shapes[{i}].link", f"a link 0 .. {n}",
                                 str(s.link))
        shapes.append(CollisionShape(link, length(s.a), length(s.a if s.b is None else s.b),
                                     float(length(s.radius)),
                                     s.link if isinstance(s.link, str) else ""))
    skip, disabled = [], []
    for i, pair in enumerate(field.skip):
        if isinstance(pair[0], str):
            unknown = [x for x in pair if x not in names]
            if unknown:
                raise ModelFileError(path, f"collision.skip[{i}]", "two link names of the "
                                     "URDF's arm" if names else "two link numbers (names only "
                                     "for a URDF robot)", found_text(unknown[0]))
            disabled.append((pair[0], pair[1]))
        elif not all(0 <= k <= n for k in pair):
            raise ModelFileError(path, f"collision.skip[{i}]", f"two links 0 .. {n}", str(pair))
        else:
            skip.append((int(pair[0]), int(pair[1])))
    radius = None if field.radius is None else float(length(field.radius))
    return CollisionSpec(radius, tuple(shapes), tuple(skip), tuple(disabled), field.adjacent)


def _body(field: BodyField, units: Units, path: str, where: str) -> Inertia:
    """A body of the inertia section in SI, in the frame the file gives it in."""
    com = units.length_to_si(field.com)
    six = units.length_to_si(units.length_to_si(field.inertia))      # kg length^2 -> kg m^2
    for key, values, bound in (("mass", [field.mass], MAX_MASS), ("com", com, MAX_LENGTH),
                               ("inertia", six, MAX_INERTIA)):
        if not (np.abs(values) <= bound).all():
            raise ModelFileError(path, f"{where}.{key}", f"values of at most {bound:g} in SI "
                                 "units", found_text(getattr(field, key)))
    try:
        return Inertia.from_six(field.mass, com, six)
    except InputError as err:
        raise ModelFileError(path, f"{where}.inertia", "a physical inertia tensor "
                             "(symmetric, principal moments >= 0)",
                             str(err).split("found ")[-1]) from None


def _inertia(spec: _RobotField, from_urdf: InertialModel | None, chain: Chain, units: Units,
             path: str) -> InertialModel | None:
    """The inertial model: the file's inertia section and its joints' armature and friction
    (or, for a URDF, the URDF's inertials with the section's payload and gravity).

    Raises
    ------
    ModelFileError
        A section that does not fit the chain (a body per moving joint), friction or armature
        without inertias, a gravity that is not 0 or 0.1 .. 100 m/s^2.
    """
    field = spec.inertia
    joints = getattr(spec, "joints", [])
    moving = [j for j in joints if j.type != "fixed"]
    for i, joint in enumerate(joints):
        given = [key for key in FRICTION_FIELDS if getattr(joint, key) is not None]
        if given and (field is None or field.links is None):
            raise ModelFileError(path, f"joints[{i}].{given[0]}", "an inertia: section with "
                                 "links (friction and armature belong to a robot with "
                                 "inertias)", "none")
    if field is None:
        return from_urdf
    if isinstance(spec, URDFFile):
        if field.links is not None:
            raise ModelFileError(path, "inertia.links", "none for a URDF robot (its <inertial> "
                                 "elements give them)", f"{len(field.links)} links")
        if from_urdf is None:
            raise ModelFileError(path, "inertia", "a URDF with <inertial> elements for a "
                                 "payload or gravity", "none in the URDF")
        model = from_urdf
    else:
        if field.links is None:
            raise ModelFileError(path, "inertia.links", f"{chain.n_joints} bodies, one per "
                                 "moving joint", "none")
        if len(field.links) != chain.n_joints:
            raise ModelFileError(path, "inertia.links", f"{chain.n_joints} bodies, one per "
                                 "moving joint", str(len(field.links)))
        links = [_body(b, units, path, f"inertia.links[{i}]")
                 for i, b in enumerate(field.links)]
        if isinstance(spec, ScrewFile):             # given in the base frame at home
            links = [b.moved(invert(T)) for b, T in zip(links, home_link_frames(chain))]
        model = InertialModel(links, **{key: [getattr(j, key) or 0.0 for j in moving]
                                        for key in FRICTION_FIELDS})
    if field.gravity is not None:
        gravity = units.length_to_si(field.gravity)
        magnitude = float(np.linalg.norm(gravity))
        if not (magnitude == 0 or 0.1 <= magnitude <= 100):
            raise ModelFileError(path, "inertia.gravity", f"0 or 0.1 .. 100 m/s^2 "
                                 f"({units.length}/s^2 in this file)",
                                 f"{magnitude:.6g} m/s^2")
        model = dataclasses.replace(model, gravity=gravity)
    if field.payload is not None:
        model = dataclasses.replace(model, payload=_body(field.payload, units, path,
                                                         "inertia.payload"))
    return model


def _check_magnitudes(spec: _RobotField, units: Units, path: str) -> None:
    """Refuse a value too large to be meant (a length over MAX_LENGTH, ...), naming its field.

    Raises
    ------
    ModelFileError
        ``joints[1].a: expected a length of at most 1000 m, found 1e+308 mm``.
    """
    def check(field: str, values, what: str, to_si, bound: float, unit: str, si_unit: str):
        values = [values] if isinstance(values, float) else values
        for value in values:
            if not abs(float(to_si(value))) <= bound:
                raise ModelFileError(path, field, f"{what} of at most {bound:g} {si_unit}",
                                     f"{value:g} {unit}".rstrip())

    def length(field, values):
        check(field, values, "a length", units.length_to_si, MAX_LENGTH, units.length, "m")

    def angle(field, values):
        check(field, values, "an angle", units.angle_to_si, MAX_ANGLE, units.angle, "rad")

    def pose(field, value: PoseField | None):
        if value is not None:
            length(f"{field}.xyz", value.xyz)
            angle(f"{field}.rpy", value.rpy)

    pose("base", spec.base)
    pose("tool", spec.tool)
    if isinstance(spec, ScrewFile):
        pose("home", spec.home)
    for i, joint in enumerate(getattr(spec, "joints", ())):
        where = f"joints[{i}]"
        if isinstance(joint, DHJointField):
            angle(f"{where}.alpha", joint.alpha)
            length(f"{where}.a", joint.a)
            length(f"{where}.d", joint.d)
            angle(f"{where}.theta", joint.theta)
        else:
            check(f"{where}.axis", joint.axis, "a direction component", float, MAX_AXIS, "", "")
            if joint.point is not None:
                length(f"{where}.point", joint.point)
        if joint.limits is not None:
            (angle if joint.type == "revolute" else length)(f"{where}.limits", joint.limits)
        revolute = joint.type == "revolute"
        to_si = units.angle_to_si if revolute else units.length_to_si
        unit, si_unit = (units.angle, "rad") if revolute else (units.length, "m")
        for key, per in (("velocity", "/s"), ("acceleration", "/s^2"), ("jerk", "/s^3")):
            value = getattr(joint, key)
            if value is not None:
                check(f"{where}.{key}", value, f"a {key} limit", to_si, MAX_RATE,
                      unit + per, si_unit + per)
        for key in ("torque",) + FRICTION_FIELDS:
            value = getattr(joint, key)
            if value is not None:
                check(f"{where}.{key}", value, f"a {key}", float, MAX_TORQUE, "", "")


def _check_unique_names(spec: _RobotField, path: str) -> None:
    """Refuse two joints of one name (given, or the q1, q2, ... of unnamed moving joints)."""
    seen: dict[str, int] = {}
    moving = 0
    for i, joint in enumerate(getattr(spec, "joints", ())):
        if joint.type == "fixed":
            if not joint.name:
                continue
            name = joint.name
        else:
            moving += 1
            # The numbering the front-ends give unnamed joints (chain_from_dh, _screw_row).
            name = joint.name or f"q{moving if isinstance(spec, DHFile) else i + 1}"
        if name in seen:
            raise ModelFileError(path, f"joints[{i}].name", "a name no other joint has",
                                 f"{found_text(name)}, the name of joints[{seen[name]}]"
                                 + ("" if joint.name else " (unnamed joints are numbered q1, "
                                    "q2, ...)"))
        seen[name] = i


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
    torque = np.inf if joint.torque is None else float(joint.torque)
    jerk = None if joint.jerk is None else float(to_si(joint.jerk))
    return Limits(lower, upper, velocity, acceleration, jerk, torque)


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


def load_robot(path: str | Path, tip: str | None = None, srdf: str | Path | None = None
               ) -> Robot:
    """Load a robot from a YAML robot file or a URDF file (.urdf or .xacro: SI units).

    Parameters
    ----------
    path : str or Path
    tip : str, optional
        URDF only: the link the chain ends at, where the tree has several leaves (a robot
        file names its own ``tip``).
    srdf : str or Path, optional
        URDF only: an SRDF whose ``disable_collisions`` pairs the collision checks leave out
        (a robot file names its own ``srdf``).

    Raises
    ------
    ModelFileError
        If the file is invalid.
    InputError
        If a tip is given for a robot file.
    """
    path = Path(path)
    if path.suffix.lower() in (".urdf", ".xacro"):
        table = read_urdf(path, tip)
        name = path.name.split(".")[0] or path.stem
        chain = chain_from_urdf(table)
        collision = None if srdf is None else CollisionSpec(
            disabled=read_srdf(srdf, _srdf_links(table)).disabled_pairs, adjacent=True)
        return Robot(name, chain, Units("m", "rad"), "", table, collision,
                     inertia_from_urdf(table, chain))
    for key, value in (("tip", tip), ("srdf", srdf)):
        if value is not None:
            raise InputError(f"{key}: expected none for a robot file (it names its own), "
                             f"found {found_text(str(value))} for {path}")
    return parse_robot(read_yaml(path, MAX_ROBOT_FILE_BYTES), str(path))


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
    if np.isfinite(limits.torque):
        doc["torque"] = _num(limits.torque)
    if np.isfinite(limits.jerk) and limits.jerk != JERK_PER_ACCELERATION * limits.acceleration:
        doc["jerk"] = _num(from_si(limits.jerk))
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
    if robot.inertia is not None:
        _inertia_doc(robot, doc)
    return doc


def _body_doc(body: Inertia, u: Units) -> dict:
    t = u.length_from_si(u.length_from_si(body.tensor))
    return {"mass": _num(body.mass), "com": _nums(u.length_from_si(body.com)),
            "inertia": _nums([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]])}


def _inertia_doc(robot: Robot, doc: dict) -> None:
    """Add the inertia section, and the joints' armature and friction, to `doc`."""
    model, u = robot.inertia, robot.units
    section: dict[str, Any] = {}
    if not isinstance(robot.table, URDFTable):
        links = model.links
        if isinstance(robot.table, ScrewTable):
            links = [b.moved(T) for b, T in zip(links, home_link_frames(robot.chain))]
        section["links"] = [_body_doc(b, u) for b in links]
        moving = [j for j in doc["joints"] if j["type"] != "fixed"]
        for key in FRICTION_FIELDS:
            values = getattr(model, key)
            for joint, value in zip(moving, () if values is None else values):
                if value != 0:
                    joint[key] = _num(value)
    if model.payload is not None:
        section["payload"] = _body_doc(model.payload, u)
    if not np.array_equal(model.gravity, InertialModel([]).gravity):
        section["gravity"] = _nums(u.length_from_si(model.gravity))
    if section:
        doc["inertia"] = section


def _collision_doc(spec: CollisionSpec, u: Units) -> dict:
    doc: dict[str, Any] = {}
    if spec.radius is not None:
        doc["radius"] = _num(u.length_from_si(spec.radius))
    if spec.shapes:
        doc["shapes"] = [{"link": s.name or s.link, "a": _nums(u.length_from_si(s.a)),
                          **({} if np.array_equal(s.a, s.b) else
                             {"b": _nums(u.length_from_si(s.b))}),
                          "radius": _num(u.length_from_si(s.radius))} for s in spec.shapes]
    if spec.skip or spec.disabled:
        doc["skip"] = [list(p) for p in spec.skip] + [list(p) for p in spec.disabled]
    if spec.adjacent:
        doc["adjacent"] = True
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


def robot(name_or_path: str | Path | Robot, folder: str | Path | None = None) -> Robot:
    """A robot from a built-in name, a YAML robot file or a URDF file.

    The one rule for every name of a robot, given or inside a file (task, scene, register map,
    hand-eye files): a built-in name (`robots`) is the built-in robot; anything else is a
    file, relative to `folder` (the folder of the file that names it) unless absolute. A file
    that happens to bear a built-in name is named with its folder (``./ur5``).

    Parameters
    ----------
    name_or_path : str, Path or Robot
        A Robot is returned as it is.
    folder : str or Path, optional
        Where a relative file name is taken from (default: the working directory).

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
    path = Path(text) if folder is None else Path(folder) / text
    try:
        is_file = path.is_file()
    except (OSError, ValueError) as err:       # too long for a file name, a NUL byte, ...
        raise InputError(f"robot: expected a built-in name or a robot file, found "
                         f"{found_text(text)} ({getattr(err, 'strerror', None) or err})") from None
    if is_file:
        return load_robot(path)
    raise InputError(f"robot: expected a built-in name ({', '.join(robots())}) or a robot file, "
                     f"found {found_text(text)}{_did_you_mean(text)}")


def _did_you_mean(text: str) -> str:
    hint = difflib.get_close_matches(text, robots(), n=1)
    return f" (did you mean {hint[0]!r}?)" if hint else ""


def robot_named_in(file: str | Path, name: str, field: str = "robot") -> Robot:
    """The robot a file names in one of its fields, by `robot`'s rule, relative to that file.

    Raises
    ------
    ModelFileError
        Naming `file` and `field` when the name is neither built in nor a loadable file (an
        invalid robot file raises its own ModelFileError, naming that file).
    """
    checked_path(name, str(file), field)        # the one path rule, before any look-up
    try:
        return robot(name, Path(file).parent)
    except ModelFileError:
        raise
    except InputError:
        raise ModelFileError(str(file), field, "a built-in robot name or a robot file",
                             found_text(name) + _did_you_mean(str(name))) from None
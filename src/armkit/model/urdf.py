"""URDF serial chains compiled into a chain.

A URDF joint places its child link at ``origin(xyz, rpy) @ M(q)``, M the motion about or along
``axis``. The chain runs from the root link to a tip link (named, or the only leaf); fixed
joints are folded into their neighbours, so link frame i is the child link of moving joint i.
Supported joint types: revolute, continuous (no position limits), prismatic, fixed.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from armkit.errors import ModelFileError
from armkit.model.chain import Chain, Joint, Limits, freeze
from armkit.spatial import pose_from_xyz_rpy

SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")


@dataclass(frozen=True)
class URDFJoint:
    """One joint of the chosen chain, as the URDF gives it (SI)."""

    name: str
    kind: str
    parent: str
    child: str
    xyz: NDArray
    rpy: NDArray
    axis: NDArray
    limits: Limits | None


@dataclass(frozen=True)
class URDFTable:
    """A URDF file, the chain chosen in it, and base and tool transforms (4, 4)."""

    path: str
    tip: str
    joints: tuple[URDFJoint, ...]
    T_base: NDArray = field(default_factory=lambda: np.eye(4))
    T_tool: NDArray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        freeze(self, "T_base", "T_tool")


def _floats(element: ET.Element | None, attribute: str, default: str, path: str,
            where: str) -> NDArray:
    text = default if element is None else element.get(attribute, default)
    try:
        values = np.array([float(v) for v in text.split()])
    except ValueError:
        raise ModelFileError(path, f"{where} {attribute}", "numbers", repr(text)) from None
    if values.shape != (3,) or not np.isfinite(values).all():
        raise ModelFileError(path, f"{where} {attribute}", "3 finite numbers", repr(text))
    values.setflags(write=False)
    return values


def _limits(element: ET.Element, kind: str, path: str, where: str) -> Limits | None:
    if kind == "fixed":
        return None
    limit = element.find("limit")
    text = limit.get("velocity", "inf") if limit is not None else "inf"
    try:
        velocity = float(text)
    except ValueError:
        raise ModelFileError(path, f"{where} <limit> velocity", "a number",
                             repr(text)) from None
    velocity = velocity if velocity > 0 else np.inf
    if kind == "continuous":
        return Limits(-np.inf, np.inf, velocity)
    if limit is None or limit.get("lower") is None or limit.get("upper") is None:
        raise ModelFileError(path, f"{where} <limit>", "lower and upper for a "
                             f"{kind} joint", "none")
    try:
        lower, upper = float(limit.get("lower")), float(limit.get("upper"))
    except ValueError:
        raise ModelFileError(path, f"{where} <limit>", "numbers for lower and upper",
                             f"{limit.get('lower')!r} and {limit.get('upper')!r}") from None
    if not lower < upper:
        raise ModelFileError(path, f"{where} <limit>", "lower < upper", f"{lower} and {upper}")
    return Limits(lower, upper, velocity)


def read_urdf(path: str | Path, tip: str | None = None) -> URDFTable:
    """Read the serial chain from the root link to `tip` out of a URDF file.

    Raises
    ------
    ModelFileError
        The file is not URDF, a joint is malformed or of an unsupported type, the tree has
        several roots, or several tips and none is named (the message lists them).
    """
    path = str(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise ModelFileError(path, "", "a readable URDF (XML) file", str(err)) from None
    if root.tag != "robot":
        raise ModelFileError(path, "", "a <robot> root element", f"<{root.tag}>")
    by_child: dict[str, URDFJoint] = {}
    parents: set[str] = set()
    for element in root.findall("joint"):
        name, kind = element.get("name", "?"), element.get("type", "?")
        where = f"joint {name!r}"
        if kind not in SUPPORTED:
            raise ModelFileError(path, f"{where} type", " or ".join(SUPPORTED), repr(kind))
        if element.find("mimic") is not None:
            raise ModelFileError(path, f"{where} <mimic>", "independent joints", "a mimic joint")
        parent, child = element.find("parent"), element.find("child")
        if parent is None or child is None:
            raise ModelFileError(path, where, "<parent link=...> and <child link=...>", "none")
        origin = element.find("origin")
        joint = URDFJoint(name, kind, parent.get("link"), child.get("link"),
                          _floats(origin, "xyz", "0 0 0", path, f"{where} <origin>"),
                          _floats(origin, "rpy", "0 0 0", path, f"{where} <origin>"),
                          _floats(element.find("axis"), "xyz", "1 0 0", path, f"{where} <axis>"),
                          _limits(element, kind, path, where))
        if kind != "fixed" and not np.linalg.norm(joint.axis) > 1e-9:
            raise ModelFileError(path, f"{where} <axis> xyz", "a non-zero direction", "0 0 0")
        by_child[joint.child] = joint
        parents.add(joint.parent)
    links = [link.get("name") for link in root.findall("link")]
    roots = [link for link in links if link not in by_child]
    if len(roots) != 1:
        raise ModelFileError(path, "<link>", "one root link", f"{len(roots)}: {roots}")
    tips = [link for link in links if link not in parents]
    if tip is None:
        if len(tips) != 1:
            raise ModelFileError(path, "tip", "the name of the tip link (the tree has several: "
                                 f"{', '.join(tips)})", "none")
        tip = tips[0]
    elif tip not in links:
        raise ModelFileError(path, "tip", f"a link of the file ({', '.join(links)})", repr(tip))
    chain, link = [], tip
    while link in by_child:
        chain.append(by_child[link])
        link = chain[-1].parent
    return URDFTable(path, tip, tuple(reversed(chain)))


def chain_from_urdf(table: URDFTable) -> Chain:
    """Compile the chain of a URDF table; fixed joints fold into their neighbours.

    Raises
    ------
    ModelFileError
        If the chain has no moving joint.
    """
    joints: list[Joint] = []
    pending = np.eye(4)
    for j in table.joints:
        origin = pose_from_xyz_rpy(j.xyz, j.rpy)
        if j.kind == "fixed":
            pending = pending @ origin
            continue
        kind = "prismatic" if j.kind == "prismatic" else "revolute"
        joints.append(Joint(j.name, kind, j.axis, j.limits, T_before=pending @ origin))
        pending = np.eye(4)
    if not joints:
        raise ModelFileError(table.path, "tip", "a chain with a moving joint", "only fixed joints")
    return Chain(joints, table.T_base, pending @ table.T_tool)

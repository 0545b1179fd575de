"""URDF files read into a `URDFTable` (`armkit.model.urdf`), the chain from root to tip.

A URDF joint places its child link at ``origin(xyz, rpy) @ M(q)``, M the motion about or along
``axis``. The chain runs from the root link to a tip link (named, or the only leaf); fixed
joints are folded into their neighbours, so link frame i is the child link of moving joint i.
Supported joint types on the chain: revolute, continuous (no position limits), prismatic,
fixed.

The structure of the whole file is checked: every link and joint named once, every joint
between two declared links, each link with at most one parent joint, no loop, one root. The
joints of the chain are checked in full: every number an ASCII decimal, finite and within a
sane range, limits ordered, velocity limits positive. Joints off the chain play no part in the
model and their numbers are not read, so a file whose gripper or legs use conventions of their
own (``velocity="0"``, ``floating``, ``planar`` and ``<mimic>`` joints) still gives its arm. On
the chain, floating and planar joints are refused. A mimic joint on the chain moves with its
leader (its value is ``multiplier * leader + offset``, as URDF defines it) and has no value of
its own in q; its leader is an independent joint of the same kind, and has the value in q
(where the leader is off the chain, as a gripper's driven finger is for a chain that ends at
the other finger, in place of its first mimic joint). The leader's limits are narrowed to keep
its mimic joints within their own. A mimic joint's velocity limit of 0, which gripper files
often give, means it has none of its own (its leader's applies).
Meshes play no part in the kinematics; those of ``<visual>`` are not read.

The ``<collision>`` elements of the links rigidly attached to the chain (its links, and the links
hanging on them through fixed joints, merged as the kinematics merges them) are read for the
arm's collision geometry (`armkit.planning.arm_geometry`): boxes, cylinders and spheres with
their ``<origin>``, each number checked as the joints' are, and meshes: the file a ``<mesh>``
names (``package://P/...`` under a folder P above the URDF or in ``ROS_PACKAGE_PATH``,
``file://``, or relative to the URDF) is read by trimesh (STL, OBJ, PLY; DAE with pycollada),
the optional ``armkit[mesh]`` extra, and its vertices kept, scaled; without trimesh, or when
the file is not found, the mesh is kept unread with a note (a mesh file that is there but
unreadable is a ModelFileError). The ``<collision>`` elements of links moved by joints off the
chain (a gripper's fingers, another arm) are not read: those links are not part of this arm.

A ``.xacro`` file is expanded by the ``xacro`` package (``pip install "armkit[xacro]"``); xacro
evaluates the file's expressions, so expand only files you trust.
"""

from __future__ import annotations

import io
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import found_text, read_bytes
from armkit.model.chain import Limits, leader_limits
from armkit.model.inertia import Inertia
from armkit.model.urdf import COLLISION_KINDS, URDFCollision, URDFJoint, URDFTable
from armkit.spatial import pose_from_xyz_rpy

SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")
ELSEWHERE_ONLY = ("floating", "planar")
"""Joint types allowed off the chosen chain only."""

MAX_URDF_BYTES = 32 * 2**20
"""The largest URDF file read (bytes); a humanoid's is about 100 kB."""

MAX_LENGTH = 1e3
"""The largest origin offset or prismatic limit (m)."""

MAX_ANGLE = 1e3
"""The largest rpy angle or revolute limit (rad)."""

MAX_RATE = 1e6
"""The largest velocity limit (rad/s or m/s)."""

MAX_AXIS = 1e3
"""The largest axis component (the axis is normalised)."""

MAX_MASS = 1e6
"""The largest link mass (kg)."""

MAX_INERTIA = 1e6
"""The largest inertia tensor entry (kg m^2)."""

MAX_TORQUE = 1e7
"""The largest effort limit (N m or N) and friction (N m, N m s/rad)."""

MAX_MESH_BYTES = 64 * 2**20
"""The largest collision mesh file read (bytes)."""

MAX_VERTICES = 2_000_000
"""The most vertices a collision mesh may have."""

# A URDF number: ASCII decimal digits only (Python's float() also takes "١٢", "1_0", "nan").
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_XML_SPACE = re.compile(r"[ \t\n\r]+")
_SHOWN_NAMES = 12


def _names(names) -> str:
    """A list of names for a message, at most _SHOWN_NAMES of them."""
    names = list(names)
    shown = ", ".join(found_text(n)[1:-1] for n in names[:_SHOWN_NAMES])
    return shown + (f", ... ({len(names)} in all)" if len(names) > _SHOWN_NAMES else "")


def _numbers(text: str, count: int, path: str, where: str, bound: float) -> NDArray:
    """`count` ASCII decimal numbers from an attribute's text, each finite and |x| <= bound."""
    tokens = [t for t in _XML_SPACE.split(text) if t]
    expected = "a finite number" if count == 1 else f"{count} finite numbers"
    if len(tokens) != count or not all(_NUMBER.fullmatch(t) for t in tokens):
        raise ModelFileError(path, where, expected, found_text(text))
    values = np.array([float(t) for t in tokens])
    if not (np.abs(values) <= bound).all():
        raise ModelFileError(path, where, f"{expected} of at most {bound:g} in size",
                             found_text(text))
    values.setflags(write=False)
    return values


def _attribute(element: ET.Element | None, attribute: str, default: str, count: int,
               path: str, where: str, bound: float) -> NDArray:
    text = default if element is None else element.get(attribute, default)
    return _numbers(text, count, path, f"{where} {attribute}", bound)


def _limits(element: ET.Element, kind: str, path: str, where: str) -> Limits | None:
    if kind not in ("revolute", "continuous", "prismatic"):
        return None
    limit = element.find("limit")
    velocity = np.inf
    if limit is not None and limit.get("velocity") is not None:
        velocity = float(_numbers(limit.get("velocity"), 1, path, f"{where} <limit> velocity",
                                  MAX_RATE)[0])
        mimic = element.find("mimic") is not None
        if velocity == 0 and mimic:
            velocity = np.inf           # gripper files' mimic joints: the leader's limit rules
        elif not velocity > 0:
            raise ModelFileError(path, f"{where} <limit> velocity", "a positive number"
                                 + (" (or 0 on a mimic joint)" if mimic else ""),
                                 found_text(limit.get("velocity")))
    torque = _effort(limit, element.find("mimic") is not None, path, where)
    if kind == "continuous":
        return Limits(-np.inf, np.inf, velocity, torque=torque)
    if limit is None or limit.get("lower") is None or limit.get("upper") is None:
        raise ModelFileError(path, f"{where} <limit>", "lower and upper for a "
                             f"{kind} joint", "none")
    bound = MAX_ANGLE if kind == "revolute" else MAX_LENGTH
    lower = float(_numbers(limit.get("lower"), 1, path, f"{where} <limit> lower", bound)[0])
    upper = float(_numbers(limit.get("upper"), 1, path, f"{where} <limit> upper", bound)[0])
    if not lower < upper:
        raise ModelFileError(path, f"{where} <limit>", "lower < upper", f"{lower} and {upper}")
    return Limits(lower, upper, velocity, torque=torque)


def _effort(limit: ET.Element | None, mimic: bool, path: str, where: str) -> float:
    """A moving joint's effort limit (N m or N); inf where none is given, and on a mimic joint
    whose effort is 0 (its leader's motor drives it)."""
    if limit is None or limit.get("effort") is None:
        return np.inf
    text = limit.get("effort")
    effort = float(_numbers(text, 1, path, f"{where} <limit> effort", MAX_TORQUE)[0])
    if effort == 0 and mimic:
        return np.inf
    if not effort > 0:
        raise ModelFileError(path, f"{where} <limit> effort", "a positive number"
                             + (" (or 0 on a mimic joint)" if mimic else ""), found_text(text))
    return effort


def _friction(element: ET.Element, path: str, where: str) -> tuple[float, float]:
    """A joint's <dynamics damping friction>: viscous (N m s/rad, N s/m) and Coulomb friction
    (N m, N), each >= 0; zero where not given."""
    dynamics = element.find("dynamics")
    values = []
    for key in ("damping", "friction"):
        text = "0" if dynamics is None else dynamics.get(key, "0")
        value = float(_numbers(text, 1, path, f"{where} <dynamics> {key}", MAX_TORQUE)[0])
        if value < 0:
            raise ModelFileError(path, f"{where} <dynamics> {key}", "a number >= 0",
                                 found_text(text))
        values.append(value)
    return values[0], values[1]


def _expand_xacro(path: str) -> bytes:
    """The URDF a .xacro file expands to, through the optional xacro package."""
    try:
        import xacro
    except ImportError:
        raise ModelFileError(path, "", "the xacro package to expand a .xacro file "
                             "(pip install \"armkit[xacro]\")", "it is not installed") from None
    try:
        document = xacro.process_file(path)
    except Exception as err:  # noqa: BLE001 - xacro raises its own, XML and lookup errors
        text = " ".join((str(err) or type(err).__name__).split())
        if "ament" in text or "package not found" in text.lower():
            # $(find pkg) looks packages up in a ROS installation (or where xacrodoc says).
            text = ("a $(find ...) package it cannot find (xacro looks packages up in a ROS "
                    "installation): write the path instead, or expand the file where ROS is")
        raise ModelFileError(path, "", "a .xacro file that expands to URDF",
                             text if len(text) <= 200 else text[:197] + "...") from None
    return document.toxml(encoding="utf-8")


@dataclass
class _Element:
    """A joint of the file as its structure gives it, before the chain is chosen."""

    element: ET.Element
    name: str
    kind: str
    parent: str
    child: str
    mimic: ET.Element | None


def _read_structure(element: ET.Element, links: set[str], path: str) -> _Element:
    """A joint's name, type and links, checked; its numbers are read only if on the chain."""
    name, kind = element.get("name"), element.get("type")
    if not name:
        raise ModelFileError(path, "<joint>", "a name attribute", "none")
    where = f"joint {found_text(name)}"
    if kind not in SUPPORTED + ELSEWHERE_ONLY:
        raise ModelFileError(path, f"{where} type", " or ".join(SUPPORTED),
                             found_text(kind) if kind is not None else "none")
    ends = {}
    for end in ("parent", "child"):
        link_element = element.find(end)
        link = None if link_element is None else link_element.get("link")
        if link is None:
            raise ModelFileError(path, f"{where} <{end}>", f"<{end} link=\"...\">", "none")
        if link not in links:
            raise ModelFileError(path, f"{where} <{end}>", "a link declared in the file",
                                 f"link {found_text(link)}, which no <link> declares")
        ends[end] = link
    return _Element(element, name, kind, ends["parent"], ends["child"], element.find("mimic"))


def _read_joint(item: _Element, path: str) -> URDFJoint:
    """A joint of the chain with its numbers, each checked."""
    element, kind = item.element, item.kind
    where = f"joint {found_text(item.name)}"
    origin = element.find("origin")
    axis = _attribute(element.find("axis"), "xyz", "1 0 0", 3, path, f"{where} <axis>",
                      MAX_AXIS)
    if kind != "fixed" and not np.linalg.norm(axis) > 1e-9:
        raise ModelFileError(path, f"{where} <axis> xyz", "a non-zero direction",
                             found_text(element.find("axis").get("xyz")))
    return URDFJoint(item.name, kind, item.parent, item.child,
                     _attribute(origin, "xyz", "0 0 0", 3, path, f"{where} <origin>",
                                MAX_LENGTH),
                     _attribute(origin, "rpy", "0 0 0", 3, path, f"{where} <origin>",
                                MAX_ANGLE),
                     axis, _limits(element, kind, path, where),
                     None if item.mimic is None else _mimic(item, path),
                     *(_friction(element, path, where) if kind != "fixed" and item.mimic is None
                       else (0.0, 0.0)))


def _mimic(item: _Element, path: str) -> tuple[str, float, float]:
    """A mimic joint's (leader, multiplier, offset)."""
    mimic, where = item.mimic, f"joint {found_text(item.name)} <mimic>"
    if item.kind == "fixed":
        raise ModelFileError(path, where, "a mimic on a moving joint", "a fixed joint")
    leader = mimic.get("joint")
    if not leader:
        raise ModelFileError(path, f"{where} joint", "the name of the joint it mimics", "none")
    bound = MAX_ANGLE if item.kind in ("revolute", "continuous") else MAX_LENGTH
    multiplier = _attribute(mimic, "multiplier", "1", 1, path, where, MAX_AXIS)[0]
    offset = _attribute(mimic, "offset", "0", 1, path, where, bound)[0]
    return leader, float(multiplier), float(offset)


def robot_element(path: str, data: bytes, kind: str) -> ET.Element:
    """The ``<robot>`` root of a URDF or SRDF document (`kind`: "URDF" or "SRDF"); entity
    declarations are refused (their expansion can blow a few bytes up to gigabytes, and no
    robot file needs them).

    Raises
    ------
    ModelFileError
    """
    if b"<!ENTITY" in data:
        article = "an" if kind == "SRDF" else "a"
        raise ModelFileError(path, "", f"{article} {kind} (XML) file without entity "
                             "declarations", "<!ENTITY ...>")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as err:
        raise ModelFileError(path, "", f"a readable {kind} (XML) file",
                             found_text(str(err))[1:-1]) from None
    if root.tag != "robot":
        raise ModelFileError(path, "", "a <robot> root element",
                             f"<{found_text(str(root.tag))[1:-1]}>")
    return root


def _parse(path: str) -> ET.Element:
    data = (_expand_xacro(path) if path.lower().endswith(".xacro") else
            read_bytes(path, MAX_URDF_BYTES))
    return robot_element(path, data, "URDF")


def read_urdf(path: str | Path, tip: str | None = None) -> URDFTable:
    """Read the serial chain from the root link to `tip` out of a URDF (or .xacro) file.

    Parameters
    ----------
    path : str or Path
        A ``.urdf`` file, or a ``.xacro`` file (needs the xacro package).
    tip : str, optional
        The link the chain ends at; by default the tree's only leaf.

    Raises
    ------
    ModelFileError
        The file is not URDF; a joint or link is malformed, unnamed or named twice; a joint
        names a link the file does not declare; a link has two parents; the joints form a
        loop; the tree has several roots, or several tips and none is named (the message lists
        them); the chain holds a floating or planar joint, or a mimic joint whose leader is
        not an independent moving joint of its own kind.
    """
    path = str(path)
    root = _parse(path)
    links: set[str] = set()
    order: list[str] = []
    for element in root.findall("link"):
        name = element.get("name")
        if not name:
            raise ModelFileError(path, "<link>", "a name attribute", "none")
        if name in links:
            raise ModelFileError(path, f"link {found_text(name)}", "a name no other link has",
                                 "it declared twice")
        links.add(name)
        order.append(name)
    read: dict[str, _Element] = {}
    parent_joint: dict[str, _Element] = {}                 # child link -> its joint
    for element in root.findall("joint"):
        joint = item = _read_structure(element, links, path)
        if joint.name in read:
            raise ModelFileError(path, f"joint {found_text(joint.name)}",
                                 "a name no other joint has", "it declared twice")
        read[joint.name] = item
        if joint.child in parent_joint:
            other = parent_joint[joint.child].name
            raise ModelFileError(path, f"link {found_text(joint.child)}",
                                 "one parent joint (a tree)", f"two: joints "
                                 f"{found_text(other)} and {found_text(joint.name)}")
        parent_joint[joint.child] = item
    if not order:
        raise ModelFileError(path, "<link>", "at least one link", "none")
    _refuse_loops(parent_joint, path)
    roots = [link for link in order if link not in parent_joint]
    if len(roots) != 1:
        raise ModelFileError(path, "<link>", "one root link (a link no joint has as child)",
                             f"{len(roots)}: {_names(roots)}")
    parents = {item.parent for item in read.values()}
    if tip is None:
        tips = [link for link in order if link not in parents]
        if len(tips) != 1:
            raise ModelFileError(path, "tip", "the name of the tip link (the tree has several: "
                                 f"{_names(tips)})", "none")
        tip = tips[0]
    elif tip not in links:
        raise ModelFileError(path, "tip", f"a link of the file ({_names(order)})",
                             found_text(tip))
    chain, link = [], tip
    while link in parent_joint:
        item = parent_joint[link]
        where = f"joint {found_text(item.name)}"
        if item.kind in ELSEWHERE_ONLY:
            raise ModelFileError(path, f"{where} type", "revolute, continuous, prismatic or "
                                 f"fixed on the chain to {found_text(tip)}",
                                 found_text(item.kind))
        chain.append(_read_joint(item, path))
        link = item.parent
    chain.reverse()
    collisions, detached = _read_collisions(root, roots[0], chain, parent_joint, path)
    inertials, carried = _read_inertials(root, roots[0], chain, parent_joint, path)
    return URDFTable(path, tip, tuple(chain), leaders=_leaders(chain, read, path),
                     collisions=collisions, detached=detached, inertials=inertials,
                     carried=carried)


def _leaders(chain: list[URDFJoint], read: dict[str, _Element], path: str
             ) -> tuple[URDFJoint, ...]:
    """The leaders off the chain of the chain's mimic joints, read; refuses a leader that is
    not an independent moving joint of the mimic's kind (revolute and continuous are one), or
    whose range cannot keep its mimic joints within their limits."""
    known = {j.name: j for j in chain}
    rotates = ("revolute", "continuous")
    off_chain = []
    for j in chain:
        if j.mimic is None:
            continue
        name, where = j.mimic[0], f"joint {found_text(j.name)} <mimic> joint"
        if name not in known:
            if name not in read:
                raise ModelFileError(path, where, "the name of a joint of the file",
                                     found_text(name))
            if read[name].kind in SUPPORTED[:3]:
                known[name] = _read_joint(read[name], path)
                off_chain.append(known[name])
        leader = known.get(name)
        if leader is None or leader.mimic is not None or leader.kind == "fixed":
            kind = read[name].kind if leader is None else (
                "mimic" if leader.mimic is not None else "fixed")
            raise ModelFileError(path, where, "an independent moving joint",
                                 f"{found_text(name)}, a {kind} joint")
        if (j.kind in rotates) != (leader.kind in rotates):
            raise ModelFileError(path, where, f"a joint of its own kind ({j.kind})",
                                 f"{found_text(name)}, {leader.kind}")
    for leader in list(chain) + off_chain:
        followers = [j for j in chain if j.mimic is not None and j.mimic[0] == leader.name]
        if followers and leader_limits(leader.limits, [(j.mimic[1], j.mimic[2], j.limits)
                                                       for j in followers]) is None:
            raise ModelFileError(path, f"joint {found_text(leader.name)} <limit>",
                                 "a range in which its mimic joints "
                                 f"({_names(j.name for j in followers)}) stay within their "
                                 "limits", "none")
    return tuple(off_chain)


def _positive(element: ET.Element, attribute: str, count: int, path: str,
              where: str) -> NDArray:
    """A required attribute of `count` positive lengths (m), each at most MAX_LENGTH."""
    text = element.get(attribute)
    expected = "a positive length (m)" if count == 1 else f"{count} positive lengths (m)"
    if text is None:
        raise ModelFileError(path, f"{where} {attribute}", expected, "none")
    values = _numbers(text, count, path, f"{where} {attribute}", MAX_LENGTH)
    if not (values > 0).all():
        raise ModelFileError(path, f"{where} {attribute}", expected, found_text(text))
    return values


def _read_collision(element: ET.Element, link: str, index: int, chain_link: int,
                    T_anchor_link: NDArray, path: str) -> URDFCollision:
    """One <collision> element, every number checked; its frame in the chain link's frame."""
    where = f"link {found_text(link)} <collision>[{index}]"
    origin = element.find("origin")
    xyz = _attribute(origin, "xyz", "0 0 0", 3, path, f"{where} <origin>", MAX_LENGTH)
    rpy = _attribute(origin, "rpy", "0 0 0", 3, path, f"{where} <origin>", MAX_ANGLE)
    geometry = element.find("geometry")
    if geometry is None:
        raise ModelFileError(path, f"{where} <geometry>", "a <geometry> element", "none")
    shapes = list(geometry)
    if len(shapes) != 1 or shapes[0].tag not in COLLISION_KINDS:
        found = ("nothing" if not shapes else
                 " ".join(f"<{found_text(str(x.tag))[1:-1]}>" for x in shapes[:4]))
        raise ModelFileError(path, f"{where} <geometry>",
                             "one of <box>, <cylinder>, <sphere> or <mesh>", found)
    shape, kind = shapes[0], shapes[0].tag
    at = f"{where} <{kind}>"
    if kind == "box":
        size = _positive(shape, "size", 3, path, at)
    elif kind == "cylinder":
        size = np.array([_positive(shape, "radius", 1, path, at)[0],
                         _positive(shape, "length", 1, path, at)[0]])
    elif kind == "sphere":
        size = _positive(shape, "radius", 1, path, at)
    else:
        size = _attribute(shape, "scale", "1 1 1", 3, path, at, MAX_AXIS)
        if not np.all(size != 0):
            raise ModelFileError(path, f"{at} scale", "3 non-zero factors",
                                 found_text(shape.get("scale")))
        found, vertices, faces, note = _read_mesh(shape.get("filename"), size, path, at)
        return URDFCollision(link, index, chain_link, kind, size,
                             T_anchor_link @ pose_from_xyz_rpy(xyz, rpy), found, vertices,
                             faces, note)
    return URDFCollision(link, index, chain_link, kind, size,
                         T_anchor_link @ pose_from_xyz_rpy(xyz, rpy))


def mesh_file(filename: str, urdf: str) -> Path | None:
    """The file a URDF's mesh filename names, or None if it cannot be found: ``package://P/x``
    under a folder named P above the URDF (or in ``ROS_PACKAGE_PATH``), ``file://x``, or a path
    relative to the URDF."""
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        roots = [p for p in Path(urdf).resolve().parents if p.name == package]
        roots += [Path(p) / package for p in os.environ.get("ROS_PACKAGE_PATH", "").split(
            os.pathsep) if p]
        for root in roots:
            if (root / rest).is_file():
                return root / rest
        return None
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    found = Path(urdf).parent / filename
    return found if found.is_file() else None


def _read_mesh(filename: str | None, scale: NDArray, path: str, where: str):
    """A <mesh>'s (file, vertices scaled (v, 3), faces (f, 3), note), read by trimesh (the
    optional ``armkit[mesh]`` extra); a file that cannot be found, or trimesh not installed,
    leaves the vertices None and says so in the note."""
    if not filename:
        raise ModelFileError(path, f"{where} filename", "a mesh file name", "none")
    found = mesh_file(filename, path)
    if found is None:
        return "", None, None, f"its file {found_text(filename)} was not found"
    try:
        import trimesh
    except ImportError:
        return str(found), None, None, ("trimesh is not installed (pip install "
                                        "\"armkit[mesh]\")")
    data = read_bytes(found, MAX_MESH_BYTES)
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type=found.suffix.lstrip(".").lower(),
                            force="mesh", process=False)
        vertices = np.asarray(mesh.vertices, dtype=float)
        faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    except ImportError as err:                  # a format needing another package (DAE)
        return str(found), None, None, f"trimesh cannot read it here ({err})"
    except Exception as err:  # noqa: BLE001 - trimesh raises its own, numpy's and parsers'
        raise ModelFileError(path, f"{where} filename", f"a mesh file trimesh reads "
                             f"({found})", found_text(str(err) or type(err).__name__)) from None
    if len(vertices) == 0 or not np.isfinite(vertices).all() or len(vertices) > MAX_VERTICES \
            or (faces.size and (faces.min() < 0 or faces.max() >= len(vertices))):
        raise ModelFileError(path, f"{where} filename", f"a mesh of 1 to {MAX_VERTICES} finite "
                             f"vertices and faces naming them ({found})",
                             f"{len(vertices)} vertices")
    return str(found), vertices * scale, faces, ""


def _read_collisions(root: ET.Element, root_link: str, chain: list[URDFJoint],
                     parent_joint: dict[str, _Element], path: str
                     ) -> tuple[tuple[URDFCollision, ...], tuple[str, ...]]:
    """The <collision> elements of the links rigidly attached to the chain, each placed in the
    frame of the chain link it hangs on (fixed joints merged, as `chain_from_urdf` merges
    them), and the names of the links with <collision> elements that joints off the chain move.
    """
    anchors = _chain_links(root_link, chain)
    collisions: list[URDFCollision] = []
    detached: list[str] = []
    origins: dict[str, NDArray] = {}                        # fixed joint name -> its origin
    for element in root.findall("link"):
        found = element.findall("collision")
        if not found:
            continue
        link = element.get("name")
        anchor, T = _anchor(link, anchors, parent_joint, origins, path)
        if anchor is None:
            detached.append(link)
            continue
        collisions.extend(_read_collision(c, link, k, anchor, T, path)
                          for k, c in enumerate(found))
    return tuple(collisions), tuple(detached)


def _chain_links(root_link: str, chain: list[URDFJoint]) -> dict[str, int]:
    """Link name -> chain link index: 0 the root, i the child of the chain's moving joint i."""
    anchors = {root_link: 0}
    moving = 0
    for joint in chain:
        if joint.kind != "fixed":
            moving += 1
            anchors[joint.child] = moving
    return anchors


def _anchor(link: str, anchors: dict[str, int], parent_joint: dict[str, _Element],
            origins: dict[str, NDArray], path: str) -> tuple[int | None, NDArray]:
    """The chain link a link hangs on through fixed joints only, and the link's frame in that
    chain link's URDF frame; (None, ...) for a link that a joint off the chain moves.
    `origins` keeps the fixed joints' origins read so far (each checked as on the chain)."""
    name, T = link, np.eye(4)
    while name not in anchors:
        item = parent_joint[name]               # every link but the root has one (a tree)
        if item.kind != "fixed":
            return None, T
        if item.name not in origins:
            where = f"joint {found_text(item.name)} <origin>"
            origin = item.element.find("origin")
            origins[item.name] = pose_from_xyz_rpy(
                _attribute(origin, "xyz", "0 0 0", 3, path, where, MAX_LENGTH),
                _attribute(origin, "rpy", "0 0 0", 3, path, where, MAX_ANGLE))
        T = origins[item.name] @ T
        name = item.parent
    return anchors[name], T


def _read_inertial(element: ET.Element, link: str, path: str) -> Inertia:
    """A link's <inertial> in its own frame, every number checked."""
    where = f"link {found_text(link)} <inertial>"
    origin = element.find("origin")
    xyz = _attribute(origin, "xyz", "0 0 0", 3, path, f"{where} <origin>", MAX_LENGTH)
    rpy = _attribute(origin, "rpy", "0 0 0", 3, path, f"{where} <origin>", MAX_ANGLE)
    mass_element, tensor_element = element.find("mass"), element.find("inertia")
    if mass_element is None or mass_element.get("value") is None:
        raise ModelFileError(path, f"{where} <mass>", "<mass value=\"...\"> (kg)", "none")
    mass = float(_numbers(mass_element.get("value"), 1, path, f"{where} <mass> value",
                          MAX_MASS)[0])
    if mass < 0:
        raise ModelFileError(path, f"{where} <mass> value", "a mass >= 0 kg",
                             found_text(mass_element.get("value")))
    if tensor_element is None:
        raise ModelFileError(path, f"{where} <inertia>", "<inertia ixx=... iyz=...> (kg m^2)",
                             "none")
    keys = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    missing = [key for key in keys if tensor_element.get(key) is None]
    if missing:
        raise ModelFileError(path, f"{where} <inertia>", "ixx, iyy, izz, ixy, ixz and iyz",
                             f"no {', '.join(missing)}")
    six = [_numbers(tensor_element.get(key), 1, path, f"{where} <inertia> {key}",
                    MAX_INERTIA)[0] for key in keys]
    try:
        inertia = Inertia.from_six(mass, [0.0, 0.0, 0.0], six)
    except InputError as err:
        raise ModelFileError(path, f"{where} <inertia>", "a physical inertia tensor (principal "
                             "moments >= 0)", str(err).split("found ")[-1]) from None
    return inertia.moved(pose_from_xyz_rpy(xyz, rpy))


def _read_inertials(root: ET.Element, root_link: str, chain: list[URDFJoint],
                    parent_joint: dict[str, _Element], path: str
                    ) -> tuple[tuple[Inertia | None, ...], tuple[str, ...]]:
    """Per moving joint of the chain, the <inertial> elements of its child link and of the
    links hanging on it through fixed joints, merged into one body in the child link's URDF
    frame (None where none has one); and the names of the links with <inertial> elements
    that joints off the chain move (not counted: not part of this arm). Links fixed to the
    root are not read: they never move."""
    anchors = _chain_links(root_link, chain)
    bodies: list[Inertia | None] = [None] * (max(anchors.values()) + 1)
    detached: list[str] = []
    origins: dict[str, NDArray] = {}
    for element in root.findall("link"):
        found = element.find("inertial")
        if found is None:
            continue
        link = element.get("name")
        anchor, T = _anchor(link, anchors, parent_joint, origins, path)
        if anchor is None:
            detached.append(link)
            continue
        if anchor == 0:                         # fixed to the base: it never moves
            continue
        body = _read_inertial(found, link, path).moved(T)
        bodies[anchor] = body if bodies[anchor] is None else bodies[anchor] + body
    return tuple(bodies[1:]), tuple(detached)


def _refuse_loops(parent_joint: dict[str, _Element], path: str) -> None:
    """Refuse joints that form a loop (following parents from a link leads back to it)."""
    done: set[str] = set()                                  # links known to reach a root
    for start in parent_joint:
        walk: list[str] = []
        on_walk: set[str] = set()
        link = start
        while link in parent_joint and link not in done:
            if link in on_walk:
                loop = walk[walk.index(link):] + [link]
                joints = [parent_joint[x].name for x in loop[:-1]]
                raise ModelFileError(path, "<joint>", "a tree of links (no loop)",
                                     f"a loop through links {_names(reversed(loop))} "
                                     f"(joints {_names(reversed(joints))})")
            walk.append(link)
            on_walk.add(link)
            link = parent_joint[link].parent
        done.update(walk)


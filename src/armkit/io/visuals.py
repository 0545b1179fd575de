"""A URDF's ``<visual>`` elements placed in the arm's link frames, for the 3-D views
(`armkit.report.view`, which draws them): meshes read by trimesh (an optional extra: ``pip
install "armkit[mesh]"``; Collada ``.dae`` files through pycollada), boxes, cylinders and
spheres by their sizes.

The visuals of the links rigidly attached to the chain are read (the chain's links, and links
hanging on them through fixed joints, placed as the kinematics merges them); links that joints
off the chain move (a gripper's fingers) are not. Mesh files are found as ROS finds them:
``package://NAME/rest`` in the nearest folder called NAME above the URDF file, ``file://`` and
plain paths relative to the URDF file. Every number is an ASCII decimal, finite and within
1000 (m, rad); a mesh file over `MAX_MESH_BYTES`, or surfaces over `MAX_FACES` triangles in all,
are not drawn. What was left out is said in `Visuals.notes`: a view draws the collision
capsules of links without visuals.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from armkit.errors import ModelFileError
from armkit.io.documents import found_text, read_bytes
from armkit.model.robot import Robot
from armkit.model.urdf import URDFTable
from armkit.spatial import pose_from_xyz_rpy

MAX_URDF_BYTES = 32 * 2**20
MAX_MESH_BYTES = 64 * 2**20
MAX_FACES = 400_000
MAX_VALUE = 1e3
NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)


@dataclass(frozen=True, eq=False)
class Visual:
    """One visual element of a link rigidly attached to the chain.

    Attributes
    ----------
    link : int
        The chain link it rides on: 0 the root, i the child link of moving joint i (as
        `armkit.fk_frames`).
    T : ndarray, (4, 4)
        Its frame in that link's frame (`armkit.fk_frames`: the last is the tool's), m.
    kind : {"mesh", "box", "cylinder", "sphere"}
    size : ndarray
        Box: (3,) edges; cylinder: (radius, length) along its z; sphere: (radius,); m.
    vertices, faces : ndarray (v, 3), (f, 3) or None
        A mesh's, in its own frame, scaled (m).
    name : str
        The URDF link that declares it and its place among that link's visuals:
        ``"link2_0"`` (as pinocchio names geometry objects).
    """

    link: int
    T: NDArray
    kind: str
    size: NDArray
    vertices: NDArray | None = None
    faces: NDArray | None = None
    name: str = ""


@dataclass(frozen=True)
class Visuals:
    """A URDF's visual elements on the chain, and what was not read, with why."""

    shapes: tuple[Visual, ...]
    notes: tuple[str, ...] = ()


def _numbers(text: str | None, default: str, count: int, path: str, where: str) -> NDArray:
    parts = (default if text is None else text).split()
    if len(parts) != count or not all(NUMBER.fullmatch(p) for p in parts):
        raise ModelFileError(path, where, f"{count} numbers", found_text(text))
    values = np.array([float(p) for p in parts])
    if not (np.isfinite(values).all() and (np.abs(values) <= MAX_VALUE).all()):
        raise ModelFileError(path, where, f"{count} finite numbers within {MAX_VALUE:g}",
                             found_text(text))
    return values


def _origin(element: ET.Element | None, path: str, where: str) -> NDArray:
    origin = None if element is None else element.find("origin")
    get = (lambda key: None) if origin is None else origin.get
    return pose_from_xyz_rpy(_numbers(get("xyz"), "0 0 0", 3, path, f"{where} <origin> xyz"),
                             _numbers(get("rpy"), "0 0 0", 3, path, f"{where} <origin> rpy"))


def mesh_file(name: str, urdf: Path) -> Path | None:
    """Where a URDF's mesh file name points: ``package://NAME/rest`` in the nearest folder
    called NAME above the URDF's folder (or beside one of them), ``file://`` and other paths
    relative to the URDF's folder; None if no such file."""
    if name.startswith("package://"):
        package, _, rest = name[len("package://"):].partition("/")
        for folder in [urdf.parent, *urdf.parent.parents]:
            for root in (folder, folder / package):
                if root.name == package and (root / rest).is_file():
                    return root / rest
        return None
    path = Path(name[len("file://"):] if name.startswith("file://") else name)
    path = path if path.is_absolute() else urdf.parent / path
    return path if path.is_file() else None


def _size(shape: ET.Element, path: str, where: str) -> NDArray:
    """The sizes of a <box>, <cylinder> or <sphere> (see `Visual.size`)."""
    get = lambda key, n: _numbers(shape.get(key), "", n, path, f"{where} {key}")
    if shape.tag == "box":
        return get("size", 3)
    if shape.tag == "sphere":
        return get("radius", 1)
    return np.r_[get("radius", 1), get("length", 1)]


def read_visuals(robot: Robot) -> Visuals | None:
    """The visual elements of the URDF `robot` was loaded from, in its link frames; None when
    the robot comes from no URDF file, or its file has no visual elements.

    Raises
    ------
    ModelFileError
        For a visual element with a bad number (file, element, expected, found).
    ImportError
        If the file has mesh visuals and trimesh is not installed.
    """
    table = robot.table
    if not isinstance(table, URDFTable) or Path(table.path).suffix.lower() != ".urdf":
        return None
    path = table.path
    urdf = Path(path)
    try:
        root = ET.fromstring(read_bytes(path, MAX_URDF_BYTES))
    except ET.ParseError as err:
        raise ModelFileError(path, "", "a URDF (XML) file", f"XML error: {err}") from None
    anchors, moving = {table.joints[0].parent: 0}, 0         # link -> chain link
    for joint in table.joints:
        if joint.kind != "fixed":
            moving += 1
            anchors[joint.child] = moving
    parents = {}                                              # child link -> its joint
    for joint in root.findall("joint"):
        child = joint.find("child")
        if child is not None:
            parents[child.get("link")] = joint
    # From the URDF frame of chain link k to armkit's link frame k (`armkit.fk_frames`): the
    # same frame, but for the last link, whose armkit frame is the tool (T_tool past it).
    last, to_tool = robot.chain.n_joints, np.linalg.inv(robot.chain.T_tool)
    shapes, notes = [], []
    faces = 0
    for element in root.findall("link"):
        name = link = element.get("name")
        visuals = element.findall("visual")
        T = np.eye(4)
        while visuals and name not in anchors:    # up through fixed joints to the chain
            joint = parents.get(name)
            if joint is None or joint.get("type") != "fixed":
                break
            T = _origin(joint, path, f"joint {found_text(joint.get('name'))}") @ T
            parent = joint.find("parent")
            name = None if parent is None else parent.get("link")
        if name not in anchors:
            continue                              # moved by a joint off the chain
        for k, visual in enumerate(visuals):
            where = f"link {found_text(link)} <visual>[{k}]"
            geometry = visual.find("geometry")
            shape = None if geometry is None or len(geometry) == 0 else geometry[0]
            frame = T @ _origin(visual, path, where)
            if anchors[name] == last:
                frame = to_tool @ frame
            if shape is None or shape.tag not in ("mesh", "box", "cylinder", "sphere"):
                notes.append(f"{where}: " + ("no geometry" if shape is None else
                                             f"<{found_text(shape.tag)[1:-1]}> not drawn"))
                continue
            label = f"{link}_{k}"
            if shape.tag != "mesh":
                shapes.append(Visual(anchors[name], frame, shape.tag,
                                     _size(shape, path, f"{where} <{shape.tag}>"), name=label))
                continue
            found = _mesh(shape, urdf, path, where, notes)
            if found is None:
                continue
            faces += len(found[1])
            if faces > MAX_FACES:
                notes.append(f"{where} and after: more than {MAX_FACES:,} triangles in all, "
                             "not drawn")
                return Visuals(tuple(shapes), tuple(notes))
            shapes.append(Visual(anchors[name], frame, "mesh", np.zeros(0), *found, name=label))
    if not shapes:
        return None
    return Visuals(tuple(shapes), tuple(notes))


def _mesh(shape: ET.Element, urdf: Path, path: str, where: str, notes: list[str]):
    """A <mesh> element's vertices (scaled) and triangles, or None with a note."""
    import trimesh

    name = shape.get("filename") or ""
    scale = _numbers(shape.get("scale"), "1 1 1", 3, path, f"{where} <mesh> scale")
    file = mesh_file(name, urdf)
    if file is None:
        notes.append(f"{where}: mesh {found_text(name)} not found")
        return None
    if file.stat().st_size > MAX_MESH_BYTES:
        notes.append(f"{where}: mesh {file.name} over {MAX_MESH_BYTES // 2**20} MiB")
        return None
    try:
        mesh = trimesh.load(file, force="mesh")
    except Exception as err:                       # a file trimesh cannot read, of any kind
        notes.append(f"{where}: mesh {file.name} unreadable ({type(err).__name__})")
        return None
    if not len(getattr(mesh, "faces", ())):
        notes.append(f"{where}: mesh {file.name} has no triangles")
        return None
    mesh.merge_vertices()              # the copies a renderer's normals need, drawn once
    return np.asarray(mesh.vertices, float) * scale, np.asarray(mesh.faces, int)

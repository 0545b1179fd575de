"""URDF serial chains as data, and compiled into a chain.

A URDF joint places its child link at ``origin(xyz, rpy) @ M(q)``, M the motion about or along
``axis``. `URDFTable` holds the chain chosen in a file (read by `armkit.io.urdf.read_urdf`),
with fixed joints still in it; `chain_from_urdf` folds the fixed joints into their neighbours,
so link frame i is the child link of moving joint i. A mimic joint on the chain moves with its
leader (its value is ``multiplier * leader + offset``, as URDF defines it) and has no value of
its own in q.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from armkit.errors import ModelFileError
from armkit.model.chain import Chain, Joint, Limits, freeze
from armkit.model.inertia import Inertia, InertialModel
from armkit.spatial import pose_from_xyz_rpy

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
    mimic: tuple[str, float, float] | None = None
    """(leader, multiplier, offset) of a mimic joint."""
    damping: float = 0.0
    """Viscous friction, ``<dynamics damping>`` (N m s/rad, N s/m); 0 on a mimic joint."""
    friction: float = 0.0
    """Coulomb friction, ``<dynamics friction>`` (N m, N); 0 on a mimic joint."""


COLLISION_KINDS = ("box", "cylinder", "sphere", "mesh")
"""The geometry elements a URDF <collision> may hold."""


@dataclass(frozen=True)
class URDFCollision:
    """One <collision> element of a link rigidly attached to the chain (SI).

    Attributes
    ----------
    link : str
        The URDF link that declares it.
    index : int
        Its place among that link's <collision> elements, from 0.
    chain_link : int
        The chain link it is fixed to: 0 the root link, i the child link of the chain's moving
        joint i (a link hanging on it through fixed joints is merged into it).
    kind : {"box", "cylinder", "sphere", "mesh"}
    size : ndarray
        Box: (3,) edge lengths along its x, y, z; cylinder: (radius, length), its axis its z;
        sphere: (radius,); mesh: (3,) its scale along x, y, z. m.
    T : ndarray, (4, 4)
        The element's frame (its <origin>, after the fixed joints between) in the URDF frame
        of the chain link.
    mesh : str
        A mesh's file, as found (empty if not found).
    vertices : ndarray, (v, 3), optional
        A mesh's vertices in the element's frame, scaled (m); None if its file was not read.
    faces : ndarray of int, (f, 3), optional
        A mesh's triangles (vertex indices).
    note : str
        Why a mesh was not read, if it was not.
    """

    link: str
    index: int
    chain_link: int
    kind: str
    size: NDArray
    T: NDArray
    mesh: str = ""
    vertices: NDArray | None = None
    faces: NDArray | None = None
    note: str = ""

    def __post_init__(self):
        freeze(self, "size", "T", "vertices")
        if self.faces is not None:
            faces = np.array(self.faces, dtype=np.int64)
            faces.setflags(write=False)
            object.__setattr__(self, "faces", faces)


@dataclass(frozen=True)
class URDFTable:
    """A URDF file, the chain chosen in it, and base and tool transforms (4, 4).

    ``collisions`` holds the <collision> elements of the links rigidly attached to the chain;
    ``detached`` names the links with <collision> elements moved by joints off the chain (not
    read: they are not part of this arm).
    """

    path: str
    tip: str
    joints: tuple[URDFJoint, ...]
    T_base: NDArray = field(default_factory=lambda: np.eye(4))
    T_tool: NDArray = field(default_factory=lambda: np.eye(4))
    leaders: tuple[URDFJoint, ...] = ()
    """Joints off the chain that mimic joints of the chain follow."""
    collisions: tuple[URDFCollision, ...] = ()
    detached: tuple[str, ...] = ()
    inertials: tuple[Inertia | None, ...] = ()
    """Per moving joint of the chain, the <inertial> elements of its child link and of the
    links fixed to it, as one body in the child link's frame; None where none has one."""
    carried: tuple[str, ...] = ()
    """Links with <inertial> elements that joints off the chain move (not counted)."""

    def __post_init__(self):
        freeze(self, "T_base", "T_tool")


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
        leader, multiplier, offset = j.mimic if j.mimic is not None else (None, 1.0, 0.0)
        joints.append(Joint(j.name, kind, j.axis, j.limits, T_before=pending @ origin,
                            leader=leader, multiplier=multiplier, mimic_offset=offset))
        pending = np.eye(4)
    if not joints:
        raise ModelFileError(table.path, "tip", "a chain with a moving joint", "only fixed joints")
    leaders = [Joint(j.name, "prismatic" if j.kind == "prismatic" else "revolute", j.axis,
                     j.limits) for j in table.leaders]
    return Chain(joints, table.T_base, pending @ table.T_tool, leaders)


def inertia_from_urdf(table: URDFTable, chain: Chain) -> InertialModel | None:
    """The inertial model of a URDF table's chain (`chain_from_urdf`'s): each moving joint's
    body from `URDFTable.inertials` (a body without <inertial> weighs nothing, as URDF
    defines it), friction from the independent joints' <dynamics>; None if no moving body has
    an <inertial> element."""
    if not any(x is not None for x in table.inertials):
        return None
    links = [Inertia(0.0) if x is None else x for x in table.inertials]
    joints = {j.name: j for j in (*table.joints, *table.leaders)}
    viscous = [joints[name].damping for name in chain.names]
    coulomb = [joints[name].friction for name in chain.names]
    return InertialModel(links, viscous=viscous, coulomb=coulomb)

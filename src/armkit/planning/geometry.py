"""The arm as spheres and capsules: declared in the robot file, from a URDF's collision elements
(its meshes covered by spheres), or derived from its joint origins; and which pairs of them are
tested against each other.

Each part (a capsule, or a sphere when its two points coincide) sits on one link: link 0 is the
base frame, link i the frame after joint i (``armkit.fk_frames``), the last one the tool frame;
its points are given in that link's frame, and it is named by its body (a URDF link's name,
else ``link k``). Without a declaration the arm is one capsule per moving joint, from the
joint's origin (its frame's origin, on its axis) to the next joint's origin (the tool's origin
for the last), with a stated radius; for a DH table these are the segments between consecutive
DH frame origins.

Which pairs are tested: never two parts of one link (they never move apart). Without an SRDF,
parts on links that are not adjacent, except the link pairs skipped (by number or name) and
those that touch in most sampled configurations. With an SRDF (`ArmGeometry.with_disabled`,
a robot file's ``srdf:``), MoveIt's rule: every pair of bodies it does not disable, adjacent
or not. `disabled_pairs` finds such a list the way MoveIt's Setup Assistant does (pairs never
in collision over many random configurations, pairs always or by default in collision,
adjacent links), for `armkit.io.srdf.write_srdf` to keep.

Precedence (`arm_geometry`): the robot file's own ``collision:`` section (its shapes, or the
default capsules of its radius), then a URDF's ``<collision>`` elements, then the default
capsules. A URDF's primitives become capsules that contain them, so that the arm's geometry
always holds the URDF's: a sphere stays a sphere, a cylinder becomes the capsule of its axis and
radius, a box the capsule along its longest edge whose radius is half the diagonal of the other
two (the box's cross-section fits in the capsule's disc, its length in the segment); a mesh
whose file was read becomes spheres that hold every vertex (`armkit.planning.spheres`). Links
that hang on a moving link through fixed joints are merged into it (their parts keep their own
names). An arm link whose URDF links have only unread meshes (no trimesh, or the file not
found) gets its default capsule instead, and the geometry's notes say so.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk_frames
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot
from armkit.model.urdf import URDFTable
from armkit.planning.spheres import TOLERANCE as MESH_TOLERANCE
from armkit.planning.spheres import spheres_from_mesh

DEFAULT_RADIUS = 0.04       # m, the default capsules' radius when the robot file gives none


@dataclass(frozen=True, eq=False)
class ArmGeometry:
    """Spheres and capsules on the links of one robot (SI): the parts of the arm.

    Attributes
    ----------
    link : ndarray of int, (m,)
        The link each part is fixed to: 0 base, i after joint i (n the last link).
    a, b : ndarray, (m, 3)
        The part's segment in its link's frame, m (a sphere: a == b).
    radius : ndarray, (m,)
        m.
    skip : tuple of (int, int)
        Link pairs never tested against each other.
    source : str
        Where the geometry comes from ("robot file", "URDF collision primitives", or the
        default).
    labels : tuple of str
        Where each part comes from, e.g. ``URDF panda_link1[0] cylinder`` (the link's
        first <collision>); empty, or one per part.
    notes : tuple of str
        What was left out or replaced (mesh collisions, links off the chain).
    names : tuple of str
        The body each part belongs to, by name (a URDF link's name; ``link k`` when the
        robot has no names); empty, or one per part. SRDF pairs are given by these names.
    disabled : tuple of (str, str)
        Body pairs never tested (an SRDF's ``disable_collisions``, or a robot file's skip by
        name).
    adjacent : bool
        Whether parts on adjacent links are tested. False (armkit's rule without an SRDF):
        never. True when an SRDF says which pairs are off (MoveIt's rule: every pair it does
        not disable is tested).
    """

    link: NDArray
    a: NDArray
    b: NDArray
    radius: NDArray
    skip: tuple[tuple[int, int], ...] = ()
    source: str = ""
    labels: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    names: tuple[str, ...] = ()
    disabled: tuple[tuple[str, str], ...] = ()
    adjacent: bool = False

    def __post_init__(self):
        link = frozen_array(self.link, np.int64).reshape(-1)
        m = link.shape[0]
        a, b = frozen_array(self.a).reshape(m, 3), frozen_array(self.b).reshape(m, 3)
        radius = frozen_array(self.radius).reshape(m)
        if not (np.isfinite(a).all() and np.isfinite(b).all() and np.all(radius > 0)
                and np.all(np.isfinite(radius))):
            raise InputError("arm geometry: expected finite points and positive radii, "
                             "found otherwise")
        if m and link.min() < 0:
            raise InputError(f"arm geometry: expected links from 0, found {link.min()}")
        skip = tuple(sorted({(min(int(i), int(j)), max(int(i), int(j))) for i, j in self.skip}))
        labels, notes = tuple(str(x) for x in self.labels), tuple(str(x) for x in self.notes)
        names = tuple(str(x) for x in self.names) or tuple(f"link {k}" for k in link)
        for what, values in (("labels", labels), ("names", names)):
            if values and len(values) != m:
                raise InputError(f"arm geometry {what}: expected one per part ({m}), "
                                 f"found {len(values)}")
        disabled = tuple(sorted({tuple(sorted((str(i), str(j)))) for i, j in self.disabled}))
        for name, v in (("link", link), ("a", a), ("b", b), ("radius", radius), ("skip", skip),
                        ("labels", labels), ("notes", notes), ("names", names),
                        ("disabled", disabled), ("adjacent", bool(self.adjacent))):
            object.__setattr__(self, name, v)

    def __len__(self) -> int:
        return self.link.shape[0]

    def self_pairs(self) -> NDArray:
        """Part index pairs (p, 2), i < j, tested for self-collision: on different links (parts
        of one link never move apart), not adjacent links unless `adjacent`, not a skipped link
        pair, not a disabled body pair."""
        m = len(self)
        i, j = np.triu_indices(m, 1)
        li, lj = self.link[i], self.link[j]
        keep = li != lj
        if not self.adjacent:
            keep &= np.abs(li - lj) > 1
        if self.skip:
            lo, hi = np.minimum(li, lj), np.maximum(li, lj)
            skip = np.array(self.skip, dtype=np.int64)
            keep &= ~np.isin(lo * (self.link.max() + 1) + hi,
                             skip[:, 0] * (self.link.max() + 1) + skip[:, 1])
        if self.disabled:
            bodies = sorted(set(self.names))
            index = {name: k for k, name in enumerate(bodies)}
            body = np.array([index[name] for name in self.names], dtype=np.int64)
            off = np.zeros((len(bodies), len(bodies)), bool)
            for x, y in self.disabled:
                if x in index and y in index:
                    off[index[x], index[y]] = off[index[y], index[x]] = True
            keep &= ~off[body[i], body[j]]
        return np.column_stack([i[keep], j[keep]]).astype(np.int64).reshape(-1, 2)

    def with_disabled(self, pairs, adjacent: bool = True) -> ArmGeometry:
        """The same parts with body pairs (names) never tested, as an SRDF's
        ``disable_collisions`` gives them; `adjacent`: test the pairs of adjacent links that
        are not disabled (MoveIt's rule, the default)."""
        return dataclasses.replace(self, disabled=tuple(self.disabled) + tuple(
            (str(x), str(y)) for x, y in pairs), adjacent=adjacent)


def link_to_body(robot: Robot) -> NDArray:
    """For each link 0..n, the transform (4, 4) taking points from the link frame to the frame
    the kernels move it with: identity for link 0 (the base frame), for link i joint i's frame
    after its motion (z on its axis)."""
    k, n = robot.chain.kernel, robot.chain.n_joints
    out = np.empty((n + 1, 4, 4))
    out[0] = np.eye(4)
    for i in range(n - 1):
        out[i + 1] = k.after[i]
    out[n] = k.links[n - 1]
    return out


def default_geometry(robot: Robot, radius: float = DEFAULT_RADIUS,
                     skip: tuple[tuple[int, int], ...] = ()) -> ArmGeometry:
    """One capsule per joint, from its origin to the next joint's origin (the tool's for the
    last), of `radius` m; a base capsule from the base origin to joint 1's origin if apart.

    Link pairs that touch in most sampled configurations are skipped (SRDF's "always"
    reason): with capsules this fat around short wrist links, they could never be apart.
    """
    k = robot.chain.kernel
    T_base = robot.chain.T_base
    to_link = np.linalg.inv(link_to_body(robot))        # body frame -> link frame
    links, A, B = [], [], []
    first = np.linalg.inv(T_base) @ k.pre[:, 3]
    if np.linalg.norm(first[:3]) > 1e-9:
        links.append(0), A.append(np.zeros(3)), B.append(first[:3])
    for i in range(robot.chain.n_joints):
        # Segment from joint i's origin to joint i+1's, rigid in joint i's moved frame.
        a_body, b_body = np.array([0.0, 0, 0, 1]), k.links[i][:, 3]
        links.append(i + 1)
        A.append((to_link[i + 1] @ a_body)[:3])
        B.append((to_link[i + 1] @ b_body)[:3])
    n = robot.chain.n_joints
    labels = ([] if len(links) == n else ["default: base to joint 1"]) + \
        [f"default: joint {i + 1} to {'the tool' if i + 1 == n else f'joint {i + 2}'}"
         for i in range(n)]
    geometry = ArmGeometry(links, A, B, np.full(len(links), float(radius)), skip,
                           "default: segments between joint origins", labels)
    return _skip_touching(robot, geometry)


def segment_distances(a: NDArray, b: NDArray, c: NDArray, e: NDArray) -> NDArray:
    """Distances (m) between the segments a-b and c-e, each (..., 3), vectorised (Ericson,
    Real-Time Collision Detection 5.1.9; a segment may be a point); (...,)."""
    d1, d2, r = b - a, e - c, a - c
    A, E = np.einsum("...i,...i", d1, d1), np.einsum("...i,...i", d2, d2)
    Fv, C, Bd = (np.einsum("...i,...i", d2, r), np.einsum("...i,...i", d1, r),
                 np.einsum("...i,...i", d1, d2))
    with np.errstate(divide="ignore", invalid="ignore"):
        den = A * E - Bd * Bd
        s = np.where(den > 1e-14 * A * E, np.clip((Bd * Fv - C * E) / den, 0, 1), 0.0)
        t = np.where(E > 1e-300, (Bd * s + Fv) / E, 0.0)
        s = np.where(t < 0, np.clip(-C / A, 0, 1), np.where(t > 1, np.clip((Bd - C) / A, 0, 1),
                                                                 s))
        s = np.where(A > 1e-300, s, 0.0)
        t = np.where(E > 1e-300, np.clip(t, 0, 1), 0.0)
        # A point against a segment: its projection.
        t = np.where((A <= 1e-300) & (E > 1e-300), np.clip(Fv / E, 0, 1), t)
    return np.linalg.norm(a + d1 * s[..., None] - c - d2 * t[..., None], axis=-1)


def part_segments(robot: Robot, geometry: ArmGeometry, Q: NDArray) -> tuple[NDArray, NDArray]:
    """The parts' world segments at the states Q (S, n): a, b, each (S, m, 3)."""
    F = fk_frames(robot, Q)[:, geometry.link]                   # (S, m, 4, 4)
    A = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.a) + F[..., :3, 3]
    B = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.b) + F[..., :3, 3]
    return A, B


def _skip_touching(robot: Robot, geometry: ArmGeometry, samples: int = 200) -> ArmGeometry:
    """Skip the link pairs whose parts touch in most configurations (SRDF's "always" reason):
    neighbours across a short wrist link, which default capsules could never hold apart."""
    pairs = geometry.self_pairs()
    if not len(pairs):
        return geometry
    lo, hi = robot.chain.sampling_limits
    Q = np.random.default_rng(0).uniform(lo, hi, (samples, robot.n))
    A, B = part_segments(robot, geometry, Q)
    i, j = pairs[:, 0], pairs[:, 1]
    d = segment_distances(A[:, i], B[:, i], A[:, j], B[:, j])             # (S, p)
    touching = np.mean(d <= geometry.radius[i] + geometry.radius[j], axis=0) > 0.5
    extra = {(int(geometry.link[x]), int(geometry.link[y])) for x, y in pairs[touching]}
    if not extra:
        return geometry
    return dataclasses.replace(geometry, skip=geometry.skip + tuple(sorted(extra)))


def disabled_pairs(robot: Robot, geometry: ArmGeometry, samples: int = 10_000, seed: int = 0,
                   always: float = 0.95, chunk: int = 500) -> tuple[tuple[str, str, str], ...]:
    """The body pairs a collision check can leave out, found as MoveIt's Setup Assistant finds
    them: ``(body a, body b, reason)``, reason one of

    - "Adjacent": the bodies are on the same link or on links joined by a joint;
    - "Default": they overlap at the default configuration (0, within the limits);
    - "Always": they overlap in at least `always` of `samples` random configurations;
    - "Never": they overlap in none of them.

    Pairs that never overlap in the samples may still meet in a configuration not sampled
    (MoveIt takes the same risk; more samples, less of it). The list is meant to be found
    once and kept (`armkit.io.srdf.write_srdf`, or a robot file's ``srdf:``).

    Parameters
    ----------
    samples : int
        Random configurations, uniform within the joint limits (seeded).
    always : float
        The share of samples in which a pair overlaps for "Always".
    chunk : int
        Configurations per vectorised step (memory: about 100 bytes per part pair each).

    Returns
    -------
    tuple of (str, str, str)
        Sorted by body names.
    """
    bodies = sorted(set(geometry.names))
    index = {name: k for k, name in enumerate(bodies)}
    body = np.array([index[name] for name in geometry.names], dtype=np.int64)
    link_of = {}
    for name, link in zip(geometry.names, geometry.link):
        link_of[name] = min(link_of.get(name, link), int(link))
    i, j = np.triu_indices(len(geometry), 1)
    keep = body[i] != body[j]
    i, j = i[keep], j[keep]
    key = np.minimum(body[i], body[j]) * len(bodies) + np.maximum(body[i], body[j])
    pair_keys, inverse = np.unique(key, return_inverse=True)
    reach = geometry.radius[i] + geometry.radius[j]

    def overlaps(Q):
        """(S, body pairs) bool: some parts of the two bodies overlap."""
        A, B = part_segments(robot, geometry, Q)
        d = segment_distances(A[:, i], B[:, i], A[:, j], B[:, j]) < reach      # (S, part pairs)
        hit = np.zeros((len(Q), len(pair_keys)), bool)
        np.logical_or.at(hit.T, inverse, d.T)
        return hit

    lo, hi = robot.chain.sampling_limits
    default = overlaps(np.clip(np.zeros(robot.n), lo, hi)[None])[0]
    rng = np.random.default_rng(seed)
    count = np.zeros(len(pair_keys), np.int64)
    for start in range(0, samples, chunk):
        Q = rng.uniform(lo, hi, (min(chunk, samples - start), robot.n))
        count += overlaps(Q).sum(axis=0)
    out = []
    for k, pair in enumerate(pair_keys):
        a, b = bodies[pair // len(bodies)], bodies[pair % len(bodies)]
        if abs(link_of[a] - link_of[b]) <= 1:
            reason = "Adjacent"
        elif default[k]:
            reason = "Default"
        elif count[k] >= always * samples:
            reason = "Always"
        elif count[k] == 0:
            reason = "Never"
        else:
            continue
        out.append((a, b, reason))
    return tuple(out)


def primitive_capsule(kind: str, size: NDArray) -> tuple[NDArray, NDArray, float]:
    """The capsule (a, b (3,) in the primitive's frame, radius, m) that contains a URDF
    collision primitive: a sphere itself; a cylinder (radius, length; axis z) the capsule of
    its axis and radius; a box (edge lengths (3,)) the capsule along its longest edge, of
    radius half the diagonal of the other two edges."""
    size = np.asarray(size, dtype=float)
    if kind == "sphere":
        return np.zeros(3), np.zeros(3), float(size[0])
    if kind == "cylinder":
        half = np.array([0.0, 0.0, size[1] / 2])
        return -half, half, float(size[0])
    if kind == "box":
        k = int(np.argmax(size))
        half = np.zeros(3)
        half[k] = size[k] / 2
        return -half, half, float(np.hypot(*np.delete(size, k)) / 2)
    raise InputError(f"collision primitive: expected box, cylinder or sphere, found {kind!r}")


def chain_link_names(robot: Robot) -> list[str]:
    """The name of each link 0 .. n: a URDF's link names (the root, then the child of each
    moving joint), else ``link k``."""
    table = robot.table
    n = robot.chain.n_joints
    if not isinstance(table, URDFTable) or not table.joints:
        return [f"link {k}" for k in range(n + 1)]
    names = [table.joints[0].parent] + [j.child for j in table.joints if j.kind != "fixed"]
    return names[:n + 1] + [f"link {k}" for k in range(len(names), n + 1)]


def urdf_geometry(robot: Robot, radius: float = DEFAULT_RADIUS,
                  skip: tuple[tuple[int, int], ...] = (), tolerance: float = MESH_TOLERANCE,
                  touching: bool = True) -> ArmGeometry | None:
    """The parts of a URDF robot's <collision> elements; None if it has none it can use.

    Each box, cylinder and sphere on a link rigidly attached to the chain becomes the capsule
    that contains it (`primitive_capsule`; a sphere stays a sphere) on the arm link it hangs
    on; each mesh whose vertices were read (`armkit.io.urdf`) becomes the spheres that cover
    it within `tolerance` m (`armkit.planning.spheres.spheres_from_mesh`). An arm link with a
    URDF link whose collisions are all unread meshes gets its default capsule
    (`default_geometry`, of `radius` m), and the notes say why. Each part is named by its URDF
    link. Link pairs are skipped as for the default capsules (adjacent links, `skip`, and,
    if `touching`, pairs touching in most sampled configurations).
    """
    table = robot.table
    if not isinstance(table, URDFTable):
        return None
    # From the URDF frame of chain link k to armkit's link frame k: the same frame, except
    # for the last link, whose armkit frame is the tool (chain.T_tool past the child link).
    to_tool = np.linalg.inv(robot.chain.T_tool)
    links, A, B, radii, labels, names = [], [], [], [], [], []
    by_link: dict[str, list] = {}
    unread: dict[str, str] = {}
    meshes = 0
    for c in table.collisions:
        by_link.setdefault(c.link, []).append(c)
        T = (to_tool if c.chain_link == robot.chain.n_joints else np.eye(4)) @ c.T
        if c.kind == "mesh":
            if c.vertices is None:
                unread[f"{c.link} <collision>[{c.index}]"] = c.note
                continue
            centres, r = spheres_from_mesh(c.vertices, c.faces, tolerance)
            centres = centres @ T[:3, :3].T + T[:3, 3]
            meshes += 1
            for k, (p, rk) in enumerate(zip(centres, r)):
                links.append(c.chain_link), A.append(p), B.append(p), radii.append(rk)
                labels.append(f"URDF {c.link}[{c.index}] mesh sphere {k}")
                names.append(c.link)
            continue
        a, b, r = primitive_capsule(c.kind, c.size)
        links.append(c.chain_link)
        A.append(T[:3, :3] @ a + T[:3, 3])
        B.append(T[:3, :3] @ b + T[:3, 3])
        radii.append(r)
        labels.append(f"URDF {c.link}[{c.index}] {c.kind}")
        names.append(c.link)
    if not links:
        return None
    notes = []
    unread_links = [name for name, found in by_link.items()
                    if all(f"{c.link} <collision>[{c.index}]" in unread for c in found)]
    unread_only = sorted({by_link[name][0].chain_link for name in unread_links})
    reasons = sorted(set(unread.values()))
    if unread_links:
        notes.append(f"mesh collisions not read (links {', '.join(unread_links)}: "
                     f"{'; '.join(reasons)}): default capsules of radius {radius * 1e3:g} mm on "
                     f"arm links {', '.join(map(str, unread_only))}")
        default = default_geometry(robot, radius)
        link_names = chain_link_names(robot)
        for k in np.flatnonzero(np.isin(default.link, unread_only)):
            links.append(int(default.link[k]))
            A.append(default.a[k])
            B.append(default.b[k])
            radii.append(float(default.radius[k]))
            labels.append(default.labels[k])
            names.append(link_names[int(default.link[k])])
    beside = [where for where in unread if where.split(" <")[0] not in unread_links]
    if beside:
        notes.append(f"mesh collisions not read beside other elements: {', '.join(beside)}")
    if meshes:
        notes.append(f"{meshes} meshes covered by spheres within {tolerance * 1e3:g} mm")
    if table.detached:
        notes.append("links moved by joints off the chain are not part of the arm: "
                     + ", ".join(table.detached))
    source = "URDF collision primitives" + (" and meshes as spheres" if meshes else "")
    geometry = ArmGeometry(links, A, B, radii, skip, source, labels, notes, names)
    return _skip_touching(robot, geometry) if touching else geometry


def arm_geometry(robot: Robot, radius: float | None = None,
                 tolerance: float = MESH_TOLERANCE) -> ArmGeometry:
    """The robot's collision geometry: its file's shapes or radius, else its URDF's collision
    elements (meshes covered by spheres), else default capsules; with the pairs its file
    leaves out (skip by link number or name, an SRDF's pairs).

    Parameters
    ----------
    radius : float, optional
        m; asks for the default capsules with this radius whatever the file declares.
    tolerance : float
        m; how far the spheres covering a URDF's meshes may reach past them.
    """
    spec = robot.collision
    skip = spec.skip if spec else ()
    if radius is not None:
        geometry = default_geometry(robot, float(radius), skip)
    elif spec is not None and spec.shapes:
        s = spec.shapes
        link_names = chain_link_names(robot)
        geometry = ArmGeometry([x.link for x in s], [x.a for x in s], [x.b for x in s],
                               [x.radius for x in s], spec.skip, "robot file",
                               [f"robot file: collision.shapes[{i}]" for i in range(len(s))],
                               names=[x.name or link_names[x.link] for x in s])
    elif spec is not None and spec.radius is not None:
        geometry = default_geometry(robot, spec.radius, skip)
    else:
        # With an SRDF its pairs decide: no sampled pass of armkit's own.
        srdf = spec is not None and spec.adjacent
        geometry = urdf_geometry(robot, DEFAULT_RADIUS, skip, tolerance, not srdf) or \
            default_geometry(robot, DEFAULT_RADIUS, skip)
    if spec is not None and spec.disabled:
        geometry = geometry.with_disabled(spec.disabled, adjacent=spec.adjacent)
    return geometry

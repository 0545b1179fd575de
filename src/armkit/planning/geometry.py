"""The arm as capsules: declared in the robot file, or derived from its joint origins.

Each capsule (a sphere when its two points coincide) sits on one link: link 0 is the base frame,
link i the frame after joint i (``armkit.fk_frames``), the last one the tool frame; its points
are given in that link's frame. Without a declaration the arm is one capsule per moving joint,
from the joint's origin (its frame's origin, on its axis) to the next joint's origin (the tool's
origin for the last), with a stated radius; for a DH table these are the segments between
consecutive DH frame origins. Self-collision is tested between capsules on links that are not
adjacent, except for the pairs skipped (like an SRDF's disable_collisions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk_frames
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot

DEFAULT_RADIUS = 0.04       # m, the default capsules' radius when the robot file gives none


@dataclass(frozen=True, eq=False)
class ArmGeometry:
    """Capsules on the links of one robot (SI).

    Attributes
    ----------
    link : ndarray of int, (m,)
        The link each capsule is fixed to: 0 base, i after joint i (n the last link).
    a, b : ndarray, (m, 3)
        The capsule's segment in its link's frame, m.
    radius : ndarray, (m,)
        m.
    skip : tuple of (int, int)
        Link pairs never tested against each other (adjacent links are never tested).
    source : str
        Where the geometry comes from ("robot file", or the default and its radius).
    """

    link: NDArray
    a: NDArray
    b: NDArray
    radius: NDArray
    skip: tuple[tuple[int, int], ...] = ()
    source: str = ""

    def __post_init__(self):
        link = frozen_array(self.link, np.int64).reshape(-1)
        m = link.shape[0]
        a, b = frozen_array(self.a).reshape(m, 3), frozen_array(self.b).reshape(m, 3)
        radius = frozen_array(self.radius).reshape(m)
        if not (np.isfinite(a).all() and np.isfinite(b).all() and np.all(radius > 0)):
            raise InputError("arm geometry: expected finite points and positive radii, "
                             "found otherwise")
        skip = tuple(sorted({(min(int(i), int(j)), max(int(i), int(j))) for i, j in self.skip}))
        for name, v in (("link", link), ("a", a), ("b", b), ("radius", radius), ("skip", skip)):
            object.__setattr__(self, name, v)

    def __len__(self) -> int:
        return self.link.shape[0]

    def self_pairs(self) -> NDArray:
        """Capsule index pairs (p, 2) tested for self-collision: links not adjacent, not skipped."""
        skip = set(self.skip)
        pairs = [(i, j) for i in range(len(self)) for j in range(i + 1, len(self))
                 if abs(self.link[i] - self.link[j]) > 1
                 and (min(self.link[i], self.link[j]), max(self.link[i], self.link[j])) not in skip]
        return np.array(pairs, dtype=np.int64).reshape(-1, 2)


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
    geometry = ArmGeometry(links, A, B, np.full(len(links), float(radius)), skip,
                           "default: segments between joint origins")
    return _skip_touching(robot, geometry)


def _skip_touching(robot: Robot, geometry: ArmGeometry, samples: int = 200) -> ArmGeometry:
    """Skip the capsule pairs that touch in most configurations (SRDF's "always" reason):
    neighbours across a short wrist link, which these capsules could never hold apart."""
    pairs = geometry.self_pairs()
    if not len(pairs):
        return geometry
    lo, hi = robot.chain.sampling_limits
    Q = np.random.default_rng(0).uniform(lo, hi, (samples, robot.n))
    F = fk_frames(robot, Q)[:, geometry.link]                   # (S, m, 4, 4)
    A = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.a) + F[..., :3, 3]
    B = np.einsum("smij,mj->smi", F[..., :3, :3], geometry.b) + F[..., :3, 3]
    extra = []
    for i, j in pairs:
        # Sampled segment distance (a fine polyline), enough to tell "mostly touching".
        t = np.linspace(0, 1, 9)[:, None, None]
        P = A[None, :, i] + t * (B - A)[None, :, i]
        R = A[None, :, j] + t * (B - A)[None, :, j]
        d = np.linalg.norm(P[:, None] - R[None], axis=-1).min(axis=(0, 1))
        if np.mean(d <= geometry.radius[i] + geometry.radius[j]) > 0.5:
            extra.append((int(geometry.link[i]), int(geometry.link[j])))
    if not extra:
        return geometry
    return ArmGeometry(geometry.link, geometry.a, geometry.b, geometry.radius,
                       geometry.skip + tuple(extra), geometry.source)


def arm_geometry(robot: Robot, radius: float | None = None) -> ArmGeometry:
    """The robot's collision geometry: its file's shapes, else default capsules.

    Parameters
    ----------
    radius : float, optional
        m; asks for the default capsules with this radius whatever the file declares.
    """
    spec = robot.collision
    if radius is not None:
        return default_geometry(robot, float(radius), spec.skip if spec else ())
    if spec is None:
        return default_geometry(robot)
    if spec.shapes:
        s = spec.shapes
        return ArmGeometry([x.link for x in s], [x.a for x in s], [x.b for x in s],
                           [x.radius for x in s], spec.skip, "robot file")
    return default_geometry(robot, spec.radius if spec.radius is not None else DEFAULT_RADIUS,
                            spec.skip)

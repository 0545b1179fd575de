"""Obstacles and scenes: boxes, spheres, cylinders and capsules placed in the robot's base frame.

Every obstacle is a value (frozen, read-only arrays, SI). Boxes, cylinders and capsules carry a
pose ``T_base_obstacle`` (4, 4); a cylinder's and a capsule's axis is the z axis of that pose,
centred on its origin (as in URDF and MoveIt). A `Scene` is an ordered, immutable collection.
The checker takes a scene in kernel form (`scene_kernel`): one row per obstacle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.spatial import as_array, as_transform

# Kernel codes of the obstacle kinds (collision.py).
BOX, SPHERE, CYLINDER, CAPSULE = 0, 1, 2, 3


def _positive(value: float, name: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a positive length (m), found {value:g}")
    return value


def _pose(T: ArrayLike | None, name: str) -> NDArray:
    T = np.eye(4) if T is None else as_transform(T, name)
    if T.shape != (4, 4):
        raise InputError(f"{name}: expected one pose (4, 4), found {T.shape}")
    T = np.array(T, dtype=float)
    T.setflags(write=False)
    return T


def _point(p: ArrayLike, name: str) -> NDArray:
    p = np.array(as_array(p, name, (3,)), dtype=float)
    if p.shape != (3,):
        raise InputError(f"{name}: expected one point (3,), found {p.shape}")
    p.setflags(write=False)
    return p


@dataclass(frozen=True, eq=False)
class Box:
    """A box of edge lengths `size` (3,) m, centred on the origin of `pose` (4, 4)."""

    size: NDArray
    pose: NDArray = field(default_factory=lambda: np.eye(4))
    name: str = ""

    def __post_init__(self):
        size = _point(self.size, "box size")
        for s in size:
            _positive(s, "box size")
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "pose", _pose(self.pose, "box pose"))

    @classmethod
    def from_bounds(cls, lower: ArrayLike, upper: ArrayLike, name: str = "") -> Box:
        """An axis-aligned box between two corners (3,) m."""
        lower, upper = _point(lower, "box lower corner"), _point(upper, "box upper corner")
        if not np.all(upper > lower):
            raise InputError(f"box: expected upper corner above lower corner on every axis, "
                             f"found {lower.tolist()} and {upper.tolist()}")
        T = np.eye(4)
        T[:3, 3] = (lower + upper) / 2
        return cls(upper - lower, T, name)


@dataclass(frozen=True, eq=False)
class Sphere:
    """A ball of `radius` m around `center` (3,) m."""

    center: NDArray
    radius: float
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "center", _point(self.center, "sphere center"))
        object.__setattr__(self, "radius", _positive(self.radius, "sphere radius"))


@dataclass(frozen=True, eq=False)
class Cylinder:
    """A solid cylinder of `radius` and `length` (m) along the z axis of `pose`, centred on it."""

    radius: float
    length: float
    pose: NDArray = field(default_factory=lambda: np.eye(4))
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "radius", _positive(self.radius, "cylinder radius"))
        object.__setattr__(self, "length", _positive(self.length, "cylinder length"))
        object.__setattr__(self, "pose", _pose(self.pose, "cylinder pose"))


@dataclass(frozen=True, eq=False)
class Capsule:
    """Points within `radius` m of the segment from `a` to `b` (3,) m."""

    a: NDArray
    b: NDArray
    radius: float
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "a", _point(self.a, "capsule a"))
        object.__setattr__(self, "b", _point(self.b, "capsule b"))
        object.__setattr__(self, "radius", _positive(self.radius, "capsule radius"))


Obstacle = Box | Sphere | Cylinder | Capsule


@dataclass(frozen=True, eq=False)
class Scene:
    """Obstacles in the robot's base frame (SI).

    Parameters
    ----------
    obstacles : sequence of Box, Sphere, Cylinder, Capsule
    """

    obstacles: tuple = ()

    def __post_init__(self):
        obstacles = tuple(self.obstacles)
        for i, o in enumerate(obstacles):
            if not isinstance(o, (Box, Sphere, Cylinder, Capsule)):
                raise InputError(f"scene obstacle {i}: expected a Box, Sphere, Cylinder or "
                                 f"Capsule, found {type(o).__name__}")
        object.__setattr__(self, "obstacles", obstacles)

    def __len__(self) -> int:
        return len(self.obstacles)

    def __iter__(self):
        return iter(self.obstacles)

    def __add__(self, other: Scene) -> Scene:
        return Scene(self.obstacles + tuple(other.obstacles))


@dataclass(frozen=True, eq=False)
class SceneKernel:
    """A scene as the kernels take it, one row per obstacle.

    kind (m,) int: BOX, SPHERE, CYLINDER, CAPSULE; inverse (m, 3, 4): base frame to the
    obstacle's frame; dims (m, 3): box half sizes, (radius, 0, 0) for a sphere, (radius, half
    length, 0) for a cylinder and a capsule; center (m, 3) and bound (m,): a ball holding the
    obstacle (broad phase).
    """

    kind: NDArray
    inverse: NDArray
    dims: NDArray
    center: NDArray
    bound: NDArray


def _inverse(T: NDArray) -> NDArray:
    R, p = T[:3, :3], T[:3, 3]
    return np.column_stack([R.T, -R.T @ p])


def _capsule_frame(a: NDArray, b: NDArray) -> tuple[NDArray, float]:
    """A pose whose z axis runs along a -> b, centred on the midpoint; and the half length."""
    d = b - a
    length = float(np.linalg.norm(d))
    T = np.eye(4)
    T[:3, 3] = (a + b) / 2
    if length > 0:
        z = d / length
        x = np.cross(np.eye(3)[np.argmin(np.abs(z))], z)
        x /= np.linalg.norm(x)
        T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    return T, length / 2


def scene_kernel(scene: Scene) -> SceneKernel:
    """The kernel form of a scene (see `SceneKernel`)."""
    m = len(scene)
    kind = np.zeros(m, np.int64)
    inverse = np.zeros((m, 3, 4))
    dims = np.zeros((m, 3))
    center = np.zeros((m, 3))
    bound = np.zeros(m)
    for i, o in enumerate(scene):
        if isinstance(o, Box):
            T, kind[i], dims[i] = o.pose, BOX, o.size / 2
            bound[i] = np.linalg.norm(o.size) / 2
        elif isinstance(o, Sphere):
            T = np.eye(4)
            T[:3, 3] = o.center
            kind[i], dims[i], bound[i] = SPHERE, (o.radius, 0, 0), o.radius
        elif isinstance(o, Cylinder):
            T, kind[i], dims[i] = o.pose, CYLINDER, (o.radius, o.length / 2, 0)
            bound[i] = np.hypot(o.radius, o.length / 2)
        else:
            T, half = _capsule_frame(o.a, o.b)
            kind[i], dims[i], bound[i] = CAPSULE, (o.radius, half, 0), o.radius + half
        inverse[i] = _inverse(T)
        center[i] = T[:3, 3]
    for a in (kind, inverse, dims, center, bound):
        a.setflags(write=False)
    return SceneKernel(kind, inverse, dims, center, bound)

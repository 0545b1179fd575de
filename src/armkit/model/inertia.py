"""Inertial parameters: what each link weighs and how its mass is spread, and what the joints
add (armature, friction); packed once per robot for the dynamics kernels.

An `Inertia` is one rigid body in a stated frame: its mass (kg), its centre of mass (m) and its
rotational inertia about the centre of mass along the frame's axes (kg m^2), as URDF's
``<inertial>`` gives it. An `InertialModel` holds one per moving joint, each in its link frame
(link frame i is the frame after moving joint i, as `armkit.fk_frames` returns it: the DH frame
of a DH row, the child link of a URDF joint), a payload in the tool frame, the joints' armature
and friction, and gravity. A `Robot` carries one (`Robot.inertia`) and, derived from it once,
its packed form (`Robot.dynamics`, a `KernelInertia`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model.chain import Chain, freeze, frozen_array
from armkit.spatial import invert, rotz, transform, translation

STANDARD_GRAVITY = 9.80665
"""m/s^2 (ISO 80000-3); gravity points along -z of the base frame unless a model says else."""


def _vector(value: ArrayLike, name: str, shape: tuple[int, ...]) -> NDArray:
    a = np.asarray(value, dtype=float)
    if a.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, found {a.shape}")
    if not np.isfinite(a).all():
        raise InputError(f"{name}: expected finite numbers, found {a.tolist()}")
    return a


@dataclass(frozen=True, eq=False)
class Inertia:
    """One rigid body's mass properties, expressed in a frame F.

    Parameters
    ----------
    mass : float
        kg, >= 0.
    com : array_like, shape (3,)
        Centre of mass in F (m).
    tensor : array_like, shape (3, 3)
        Rotational inertia about the centre of mass, along F's axes (kg m^2): symmetric and
        positive semi-definite (principal moments >= 0, to rounding).

    Raises
    ------
    InputError
        A negative or non-finite mass, a centre that is not 3 finite numbers, or a tensor that
        is not a symmetric positive semi-definite 3 x 3 matrix.

    Example
    -------
    >>> rod = Inertia.rod(2.0, 0.5)                # 2 kg, 0.5 m along x from F's origin
    >>> rod.com, float(rod.tensor[2, 2])
    (array([0.25, 0.  , 0.  ]), 0.041666666666666664)
    """

    mass: float
    com: NDArray = field(default_factory=lambda: np.zeros(3))
    tensor: NDArray = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self):
        mass = float(self.mass)
        if not (np.isfinite(mass) and mass >= 0.0):
            raise InputError(f"mass: expected a finite mass >= 0 kg, found {self.mass}")
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "com", frozen_array(_vector(self.com, "com", (3,))))
        tensor = _vector(self.tensor, "tensor", (3, 3))
        scale = max(np.abs(tensor).max(), 1e-300)
        if not np.allclose(tensor, tensor.T, rtol=0.0, atol=1e-9 * scale):
            raise InputError(f"tensor: expected a symmetric 3 x 3 matrix, found "
                             f"{tensor.tolist()}")
        tensor = (tensor + tensor.T) / 2
        least = np.linalg.eigvalsh(tensor)[0]
        if least < -1e-9 * scale:
            raise InputError(f"tensor: expected principal moments >= 0 (a positive "
                             f"semi-definite matrix), found {least:.6g} kg m^2")
        object.__setattr__(self, "tensor", frozen_array(tensor))

    @classmethod
    def from_six(cls, mass: float, com: ArrayLike, six: ArrayLike) -> Inertia:
        """From the six numbers ``ixx iyy izz ixy ixz iyz`` (kg m^2) about the centre of mass."""
        ixx, iyy, izz, ixy, ixz, iyz = _vector(six, "inertia", (6,))
        return cls(mass, com, [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])

    @classmethod
    def rod(cls, mass: float, length: float, radius: float = 0.0,
            axis: ArrayLike = (1.0, 0.0, 0.0)) -> Inertia:
        """A uniform solid cylinder (a rod for radius 0) from F's origin along `axis` (m)."""
        axis = _vector(axis, "axis", (3,))
        axis = axis / np.linalg.norm(axis)
        across = mass * (3 * radius ** 2 + length ** 2) / 12
        along = mass * radius ** 2 / 2
        tensor = across * np.eye(3) + (along - across) * np.outer(axis, axis)
        return cls(mass, axis * length / 2, tensor)

    @classmethod
    def tube(cls, mass: float, start: ArrayLike, end: ArrayLike, outer: float,
             inner: float) -> Inertia:
        """A uniform thin-walled or thick tube (hollow cylinder) between two points of F (m),
        radii `outer` > `inner` >= 0; a zero-length tube is a solid sphere of radius `outer`."""
        start, end = _vector(start, "start", (3,)), _vector(end, "end", (3,))
        length = float(np.linalg.norm(end - start))
        if length == 0.0:
            return cls(mass, start, 0.4 * mass * outer ** 2 * np.eye(3))
        axis = (end - start) / length
        across = mass * (3 * (outer ** 2 + inner ** 2) + length ** 2) / 12
        along = mass * (outer ** 2 + inner ** 2) / 2
        tensor = across * np.eye(3) + (along - across) * np.outer(axis, axis)
        return cls(mass, (start + end) / 2, tensor)

    def moved(self, T_new_F: ArrayLike) -> Inertia:
        """The same body expressed in another frame, given F's pose (4, 4) in it."""
        T = np.asarray(T_new_F, dtype=float)
        R = T[:3, :3]
        return Inertia(self.mass, R @ self.com + T[:3, 3], R @ self.tensor @ R.T)

    def __add__(self, other: Inertia) -> Inertia:
        """The two bodies as one rigid body (both in the same frame)."""
        mass = self.mass + other.mass
        if mass == 0.0:
            return Inertia(0.0)
        com = (self.mass * self.com + other.mass * other.com) / mass
        tensor = self.tensor + other.tensor
        for body in (self, other):
            d = body.com - com
            tensor = tensor + body.mass * (d @ d * np.eye(3) - np.outer(d, d))
        return Inertia(mass, com, tensor)

    def parameters(self) -> NDArray:
        """The 10 numbers the kernels take: ``m, m cx, m cy, m cz`` and the rotational
        inertia about F's origin ``Ixx Iyy Izz Ixy Ixz Iyz`` (kg, kg m, kg m^2)."""
        c, m = self.com, self.mass
        about = self.tensor + m * (c @ c * np.eye(3) - np.outer(c, c))
        return np.array([m, *(m * c), about[0, 0], about[1, 1], about[2, 2], about[0, 1],
                         about[0, 2], about[1, 2]])


def _per_joint(value: ArrayLike | None, name: str, n: int) -> NDArray:
    """A per-joint-value array (n,) of finite numbers >= 0 (zeros if None)."""
    if value is None:
        return frozen_array(np.zeros(n))
    a = np.broadcast_to(np.asarray(value, dtype=float), (n,)) if np.ndim(value) == 0 else \
        np.asarray(value, dtype=float)
    if a.shape != (n,):
        raise InputError(f"{name}: expected {n} values (one per joint), found shape {a.shape}")
    if not (np.isfinite(a).all() and (a >= 0).all()):
        raise InputError(f"{name}: expected finite values >= 0, found {a.tolist()}")
    return frozen_array(a)


@dataclass(frozen=True, eq=False)
class InertialModel:
    """A robot's inertial parameters (SI), beside its chain.

    Parameters
    ----------
    links : sequence of Inertia
        One per moving joint (``chain.n_joints``, mimic joints included), base to tool, each
        in its link frame (link frame i: ``armkit.fk_frames(robot, q)[..., i + 1, :, :]`` for
        i < n_joints - 1; the last link's frame is the tool frame's parent, see
        `link_frames_to_kernel`).
    payload : Inertia, optional
        A load held at the tool, in the tool frame.
    armature : array_like, shape (n,), optional
        Motor and gear inertia reflected to each joint value (kg m^2, or kg for a prismatic
        joint): adds ``armature * qdd`` to the torque.
    viscous, coulomb : array_like, shape (n,), optional
        Joint friction ``viscous * qd + coulomb * sign(qd)`` (N m s/rad and N m; N s/m and N
        for prismatic joints), added to the torque the motors give.
    gravity : array_like, shape (3,)
        Gravitational acceleration in the base (world) frame, m/s^2; ``(0, 0, -9.80665)`` by
        default.

    A scalar armature or friction is the same for every joint; None is zero.
    """

    links: tuple[Inertia, ...]
    payload: Inertia | None = None
    armature: NDArray | None = None
    viscous: NDArray | None = None
    coulomb: NDArray | None = None
    gravity: NDArray = field(default_factory=lambda: np.array([0.0, 0.0, -STANDARD_GRAVITY]))

    def __post_init__(self):
        links = tuple(self.links)
        if not all(isinstance(x, Inertia) for x in links):
            raise InputError("links: expected an Inertia per moving joint")
        if self.payload is not None and not isinstance(self.payload, Inertia):
            raise InputError(f"payload: expected an Inertia or None, found "
                             f"{type(self.payload).__name__}")
        object.__setattr__(self, "links", links)
        object.__setattr__(self, "gravity",
                           frozen_array(_vector(self.gravity, "gravity", (3,))))
        for name in ("armature", "viscous", "coulomb"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, np.asarray(value, dtype=float))
        freeze(self, "armature", "viscous", "coulomb")

    @property
    def mass(self) -> float:
        """The moving links' mass and the payload's (kg)."""
        return sum(x.mass for x in self.links) + (self.payload.mass if self.payload else 0.0)


def link_frames_to_kernel(chain: Chain) -> NDArray:
    """(n_joints, 4, 4): link frame i in the kernel's frame of moving joint i (after its
    motion, z its axis). The last link frame is the tool frame's parent: the tool pose is
    ``link frame @ chain.T_tool``."""
    k = chain.kernel
    last = k.links[-1] @ invert(chain.T_tool)
    return np.concatenate([k.after, last[None]])


def home_link_frames(chain: Chain) -> NDArray:
    """(n_joints, 4, 4): every link frame in the base frame at q = 0 (each joint at its
    offset), walked along the chain's kernel form."""
    k = chain.kernel
    T, frames = k.pre, []
    for kind, offset, link, to_link in zip(k.kinds, k.offsets, k.links,
                                           link_frames_to_kernel(chain)):
        T = T @ (transform(rotz(offset)) if kind == 0 else translation([0.0, 0.0, offset]))
        frames.append(T @ to_link)
        T = T @ link
    return np.array(frames)


@dataclass(frozen=True, eq=False)
class KernelInertia:
    """A robot's chain and inertial parameters packed for the dynamics kernels (read-only).

    ``floats`` continues the chain's packed floats (`armkit.model.chain.KernelChain`: its
    fields keep their places, so the kinematic core's steps read it unchanged), then gravity
    (3), then per moving joint i the 10 numbers of `Inertia.parameters` of its body in the
    kernel's joint frame i (the payload folded into the last), then armature, viscous and
    coulomb friction (n each). One float array and the chain's ``ints`` are what a dynamics
    kernel takes: each array more that crosses numba's dispatcher costs about as much as a
    small kernel's arithmetic. `armkit.dynamics.kernels` reads the fields through named
    accessors.
    """

    floats: NDArray
    ints: NDArray
    n: int

    def with_gravity(self, gravity: ArrayLike) -> KernelInertia:
        """The same robot under another gravity (3,), m/s^2 in the base frame."""
        floats = np.array(self.floats)
        start = floats.shape[0] - 10 * (self.ints.shape[0] // 2) - 3 * self.n - 3
        floats[start:start + 3] = _vector(gravity, "gravity", (3,))
        return KernelInertia(frozen_array(floats), self.ints, self.n)

    def without_friction(self) -> KernelInertia:
        """The same robot with no joint friction (the rigid bodies and armature only)."""
        floats = np.array(self.floats)
        floats[floats.shape[0] - 2 * self.n:] = 0.0
        return KernelInertia(frozen_array(floats), self.ints, self.n)


def pack_inertia(chain: Chain, model: InertialModel) -> KernelInertia:
    """The packed form of `model` on `chain` (see `KernelInertia`).

    Raises
    ------
    InputError
        If the model does not have one link per moving joint, or per-joint arrays of n.
    """
    nj, n = chain.n_joints, chain.n
    if len(model.links) != nj:
        raise InputError(f"links: expected {nj} inertias (one per moving joint), found "
                         f"{len(model.links)}")
    per_joint = [_per_joint(getattr(model, name), name, n)
                 for name in ("armature", "viscous", "coulomb")]
    to_kernel = link_frames_to_kernel(chain)
    bodies = [link.moved(T) for link, T in zip(model.links, to_kernel)]
    if model.payload is not None:
        bodies[-1] = bodies[-1] + model.payload.moved(chain.kernel.links[-1])
    floats = np.concatenate([chain.kernel.floats, model.gravity,
                             *(b.parameters() for b in bodies), *per_joint])
    return KernelInertia(frozen_array(floats), chain.kernel.ints, n)

"""A robot: its chain, plus the name, units and source table that people and files speak in."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.model.chain import Chain
from armkit.model.inertia import InertialModel, KernelInertia, pack_inertia


@dataclass(frozen=True)
class Units:
    """The units a robot file and the command line speak in; everything inside is SI.

    Parameters
    ----------
    length : {"m", "mm"}
    angle : {"rad", "deg"}
    """

    length: Literal["m", "mm"] = "m"
    angle: Literal["rad", "deg"] = "rad"

    def __post_init__(self):
        if self.length not in ("m", "mm") or self.angle not in ("rad", "deg"):
            raise InputError(f"units: expected length m or mm and angle rad or deg, found "
                             f"{self.length!r} and {self.angle!r}")

    def of_joint(self, revolute: bool) -> str:
        """The unit of a joint's value: the angle unit (revolute) or the length unit."""
        return self.angle if revolute else self.length

    # mm -> m divides by 1000 (correctly rounded for decimal file values such as 525.5);
    # deg <-> rad goes through numpy's deg2rad / rad2deg.
    def length_to_si(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        return x / 1000.0 if self.length == "mm" else x

    # A value too large for the file's units becomes inf, which the caller reports as such.
    def length_from_si(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        with np.errstate(over="ignore"):
            return x * 1000.0 if self.length == "mm" else x

    def angle_to_si(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        return np.deg2rad(x) if self.angle == "deg" else x

    def angle_from_si(self, x: ArrayLike) -> NDArray:
        x = np.asarray(x, dtype=float)
        with np.errstate(over="ignore"):
            return np.rad2deg(x) if self.angle == "deg" else x


SI = Units()


@dataclass(frozen=True, eq=False)
class Robot:
    """What a robot is: a chain of joints, with the description it was compiled from.

    Parameters
    ----------
    name : str
    chain : Chain
        The canonical chain every kinematics function works on (SI).
    units : Units
        The units of the robot's file; used at the edges (files, command line) only.
    description : str
    table : DHTable, ScrewTable, URDFTable or None
        The source description in SI, kept for display, saving and kinematic calibration.
    collision : CollisionSpec or None
        The collision geometry the robot file declares (`armkit.model.collision`), if any.
    inertia : InertialModel or None
        The links' masses and inertias, payload, armature, friction and gravity
        (`armkit.model.inertia`); None for a robot without them (dynamics then refuse it).

    Attributes
    ----------
    dynamics : KernelInertia or None
        The chain and `inertia` packed for the dynamics kernels, built with the robot.
    """

    name: str
    chain: Chain
    units: Units = SI
    description: str = ""
    table: object = None
    collision: object = None
    inertia: InertialModel | None = None
    dynamics: KernelInertia | None = field(init=False, repr=False, default=None)

    def __post_init__(self):
        if self.inertia is not None:
            object.__setattr__(self, "dynamics", pack_inertia(self.chain, self.inertia))

    @property
    def n(self) -> int:
        """Number of joint values q holds: the independent moving joints (not mimic ones)."""
        return self.chain.n

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.chain.names

    @property
    def joint_units(self) -> tuple[str, ...]:
        """Each joint value's unit in the robot's file ("deg", "mm", ...)."""
        return tuple(self.units.of_joint(r) for r in self.chain.revolute)

    @property
    def lower(self) -> NDArray:
        """Lower position limits (n,), rad or m."""
        return self.chain.lower

    @property
    def upper(self) -> NDArray:
        """Upper position limits (n,), rad or m."""
        return self.chain.upper

    @property
    def velocity_limits(self) -> NDArray:
        """Velocity limits (n,), rad/s or m/s; inf where the robot's file gives none."""
        return self.chain.velocity_limits

    @property
    def acceleration_limits(self) -> NDArray:
        """Acceleration limits (n,), rad/s^2 or m/s^2; inf where the robot's file gives none."""
        return self.chain.acceleration_limits

    @property
    def jerk_limits(self) -> NDArray:
        """Jerk limits (n,), rad/s^3 or m/s^3: the robot file's, else 10 times the
        acceleration limits (`armkit.model.chain.JERK_PER_ACCELERATION`)."""
        return self.chain.jerk_limits

    @property
    def torque_limits(self) -> NDArray:
        """Torque limits (n,), N m or N; inf where the robot's file gives none."""
        return self.chain.torque_limits

    @property
    def sampling_limits(self) -> tuple[NDArray, NDArray]:
        """Ranges to draw joint values from, (n,) each: the position limits, and one turn for
        a revolute joint without them (see `Chain.sampling_limits`)."""
        return self.chain.sampling_limits

    def q_to_si(self, q: ArrayLike) -> NDArray:
        """Joint values (..., n) from file units (deg, mm, ...) to rad and m."""
        q = joint_array(self, q)
        return np.where(self.chain.revolute, self.units.angle_to_si(q), self.units.length_to_si(q))

    def q_from_si(self, q: ArrayLike) -> NDArray:
        """Joint values (..., n) from rad and m to file units."""
        q = joint_array(self, q)
        return np.where(self.chain.revolute, self.units.angle_from_si(q),
                        self.units.length_from_si(q))

    def __repr__(self) -> str:
        kinds = "".join("R" if r else "P" for r in self.chain.revolute)
        return f"Robot({self.name!r}, {self.n} joints {kinds}, units {self.units.length}/{self.units.angle})"


def joint_array(robot: Robot, q: ArrayLike, name: str = "q") -> NDArray:
    """`q` as a C-contiguous float array (..., n) of finite joint values for `robot`.

    Raises
    ------
    InputError
        ``q: expected last axis 6 (the joints of ur5), found 4``, a non-finite value, or
        booleans, complex numbers or text where joint values belong.
    """
    if type(q) is np.ndarray and q.dtype == np.float64:
        a = q
    else:
        kind = np.asarray(q).dtype.kind if not isinstance(q, np.ndarray) else q.dtype.kind
        if kind not in "fiuO":
            what = {"b": "booleans", "c": "complex numbers", "U": "text", "S": "bytes"}
            raise InputError(f"{name}: expected real joint values, found "
                             f"{what.get(kind, f'an array of dtype {np.asarray(q).dtype}')}")
        try:
            a = np.asarray(q, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name}: expected numbers, found {type(q).__name__}") from None
    if a.ndim == 0 or a.shape[-1] != robot.n:
        found = a.shape[-1] if a.ndim else "a scalar"
        raise InputError(f"{name}: expected last axis {robot.n} (the joints of {robot.name}), "
                         f"found {found}")
    a = np.ascontiguousarray(a)
    if not all_finite(a):
        raise InputError(f"{name}: expected finite joint values, found NaN or inf")
    return a


def all_finite(a: NDArray) -> bool:
    """Whether every value of the float array `a` is finite, in bounded extra memory."""
    if a.size <= 64:        # a Python check is several times cheaper than two ufunc calls
        return all(map(math.isfinite, a.ravel().tolist()))
    flat = a.reshape(-1)
    step = 1 << 20          # values per block: 1 MB of flags at a time, however large `a` is
    return all(bool(np.isfinite(flat[i:i + step]).all()) for i in range(0, flat.size, step))

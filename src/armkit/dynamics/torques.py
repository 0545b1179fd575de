"""Torques along motions: a trajectory's torque profile against the limits, and the torque
constraint that `armkit.retime` holds (`TorqueLimits`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.dynamics.equations import inverse_dynamics, packed
from armkit.errors import InputError
from armkit.model.chain import frozen_array
from armkit.model.robot import Robot

if TYPE_CHECKING:
    from armkit.trajectory.piecewise import Trajectory

SAMPLES = 10_000
"""Times a trajectory's torques are sampled at by default (uniform, plus its breaks)."""


def _limits(robot: Robot, limits: ArrayLike | None) -> NDArray:
    """Torque limits (n,): the robot's, or the given ones (positive; inf for none)."""
    if limits is None:
        return robot.torque_limits
    value = np.broadcast_to(np.asarray(limits, dtype=float), (robot.n,)) \
        if np.ndim(limits) == 0 else np.asarray(limits, dtype=float)
    if value.shape != (robot.n,) or not (value > 0).all() or np.isnan(value).any():
        raise InputError(f"limits: expected {robot.n} positive torque limits (N m, N; inf for "
                         f"none), found {np.asarray(limits).tolist()}")
    return frozen_array(value)


@dataclass(frozen=True, eq=False)
class TorqueLimits:
    """A robot's torque limits and dynamics, as `armkit.retime` takes them (``torque=``).

    Parameters
    ----------
    robot : Robot
        With inertial parameters; its payload, friction and armature count.
    limits : array_like, shape (n,), optional
        N m (N for prismatic joints); the robot's own (``robot.torque_limits``) by default;
        inf where a joint has none.
    gravity : array_like, shape (3,), optional
        m/s^2 in the base frame; the robot's own by default.

    Example
    -------
    >>> ur5 = armkit.robot("ur5")
    >>> path = np.deg2rad([[0, -90, 90, 0, 0, 0], [90, -45, 45, 30, 0, 0]])
    >>> timed = armkit.retime(path, ur5.velocity_limits, 10.0, torque=TorqueLimits(ur5))
    >>> timed.success
    True
    """

    robot: Robot
    limits: NDArray | None = None
    gravity: NDArray | None = None

    def __post_init__(self):
        packed(self.robot, self.gravity)
        object.__setattr__(self, "limits", _limits(self.robot, self.limits))
        if self.gravity is not None:
            object.__setattr__(self, "gravity", frozen_array(self.gravity))

    def torques(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> NDArray:
        """Joint torques (..., n) of the motion (q, qd, qdd), friction included."""
        return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)

    def terms(self, q: NDArray, dq: NDArray, ddq: NDArray) -> tuple[NDArray, ...]:
        """Along a path q(s) (k, n) with q'(s) and q''(s): (a, b, c, d, f), each (k, n), with
        the torque ``a u + b sd^2 + c + d sd + f sign(q')`` at ds/dt = sd > 0 and
        d2s/dt2 = u.

        a = M q' (armature included), b = M q'' + C(q, q') q', c = g(q), d = viscous q',
        f = coulomb.
        """
        zero = np.zeros_like(q)
        robot = self.robot
        c = inverse_dynamics(robot, q, zero, zero, gravity=self.gravity)
        a = inverse_dynamics(robot, q, zero, dq, gravity=np.zeros(3))
        # The rigid bodies' velocity terms only: friction is d and f.
        b = inverse_dynamics(robot, q, dq, ddq, gravity=np.zeros(3)) - _friction(robot, dq)
        model = robot.inertia
        coulomb = 0.0 if model.coulomb is None else model.coulomb
        viscous = 0.0 if model.viscous is None else model.viscous
        return a, b, c, viscous * dq + zero, coulomb + zero


def _friction(robot: Robot, qd: NDArray) -> NDArray:
    """viscous qd + coulomb sign(qd), the joint friction of `robot.inertia` (k, n)."""
    model = robot.inertia
    total = np.zeros_like(qd)
    if model.viscous is not None:
        total = total + model.viscous * qd
    if model.coulomb is not None:
        total = total + model.coulomb * np.sign(qd)
    return total


@dataclass(frozen=True, eq=False)
class TorqueProfile:
    """The joint torques along a trajectory, against the limits.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Sample times (s): uniform over the trajectory, with its breaks.
    torque : ndarray, shape (k, n)
        Joint torques (N m, N) at those times.
    limits : ndarray, shape (n,)
        The limits checked against (inf where none).
    peak : ndarray, shape (n,)
        Largest |torque| of each joint.
    peak_time : ndarray, shape (n,)
        When each joint's peak is reached (s).
    ratio : ndarray, shape (n,)
        peak / limit (0 where there is no limit).
    within : bool
        Whether every peak is within its limit.
    """

    t: NDArray
    torque: NDArray
    limits: NDArray
    peak: NDArray = field(init=False)
    peak_time: NDArray = field(init=False)
    ratio: NDArray = field(init=False)
    within: bool = field(init=False)

    def __post_init__(self):
        size = np.abs(self.torque)
        index = np.argmax(size, axis=0)
        peak = size[index, np.arange(size.shape[1])]
        object.__setattr__(self, "peak", frozen_array(peak))
        object.__setattr__(self, "peak_time", frozen_array(self.t[index]))
        with np.errstate(divide="ignore"):
            ratio = np.where(np.isfinite(self.limits), peak / self.limits, 0.0)
        object.__setattr__(self, "ratio", frozen_array(ratio))
        object.__setattr__(self, "within", bool((ratio <= 1.0).all()))
        for name in ("t", "torque", "limits"):
            object.__setattr__(self, name, frozen_array(getattr(self, name)))

    def to_dict(self) -> dict:
        """Peaks, limits and ratios per joint (JSON-ready; inf limits as None)."""
        def listed(a):
            return [float(x) if np.isfinite(x) else None for x in a]

        return {"within": self.within, "peak": listed(self.peak),
                "peak_time": listed(self.peak_time), "limits": listed(self.limits),
                "ratio": listed(self.ratio)}


def torque_profile(robot: Robot, trajectory: Trajectory, *, limits: ArrayLike | None = None,
                   samples: int = SAMPLES, gravity: ArrayLike | None = None) -> TorqueProfile:
    """The joint torques a trajectory needs, sampled in time, and their peaks against the
    limits.

    Parameters
    ----------
    robot : Robot
        With inertial parameters (payload, friction, armature count).
    trajectory : Trajectory
        Joint motion in SI (`armkit.Trajectory`).
    limits : array_like, shape (n,), optional
        Torque limits (N m, N); the robot's own by default.
    samples : int
        Uniform sample times (the trajectory's breaks are added, so that each piece is seen
        at its start).
    gravity : array_like, shape (3,), optional
        m/s^2 in the base frame; the robot's own by default.

    Returns
    -------
    TorqueProfile

    Raises
    ------
    InputError
        A robot without inertias, a trajectory of another number of joints, bad limits.

    Example
    -------
    >>> ur5 = armkit.robot("ur5")
    >>> move = armkit.quintic(np.zeros(6), np.deg2rad([90, -90, 90, 0, 0, 0]), 2.0)
    >>> profile = torque_profile(ur5, move)
    >>> profile.within, profile.peak.round(1)
    (True, array([ 8.2, 58.5, 17. ,  0.4,  0.1,  0. ]))
    """
    packed(robot, gravity)
    if trajectory.n != robot.n:
        raise InputError(f"trajectory: expected {robot.n} joints (the joints of {robot.name}), "
                         f"found {trajectory.n}")
    if not (isinstance(samples, (int, np.integer)) and 2 <= samples <= 10_000_000):
        raise InputError(f"samples: expected a whole number 2 .. 1e7, found {samples!r}")
    t = np.union1d(np.linspace(trajectory.start, trajectory.end, int(samples)),
                   trajectory.breaks)
    motion = trajectory.sample(t)
    torque = inverse_dynamics(robot, motion.q, motion.qd, motion.qdd, gravity=gravity)
    return TorqueProfile(t, torque, _limits(robot, limits))

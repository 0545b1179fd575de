"""The equations of motion of a serial arm, batch-first:

    tau = M(q) qdd + C(q, qd) qd + g(q) + armature qdd + viscous qd + coulomb sign(qd)

tau the joint torques the motors give (N m for revolute, N for prismatic joints), M the
joint-space mass matrix (armature on its diagonal), C qd the Coriolis and centrifugal torques,
g the gravity torques. SI throughout: q in rad and m, qd in /s, qdd in /s^2; gravity in the
robot's base (world) frame, m/s^2 (``robot.inertia.gravity`` unless given per call).

Every function takes q, qd, qdd, tau of shape (..., n) (leading shapes broadcast against each
other) and returns (..., n) or (..., n, n). One configuration of C-contiguous float arrays goes
straight to its compiled kernel (`armkit.dynamics.kernels`); a batch runs serial or parallel as
forward kinematics does.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.dynamics import kernels
from armkit.errors import InputError
from armkit.kinematics import core
from armkit.model.inertia import Inertia, KernelInertia
from armkit.model.robot import Robot, joint_array

FLOAT = np.dtype(np.float64)
LIGHT_CONFIGURATIONS = 64   # a batch run as Python before its kernel is compiled (about 0.2 ms
#                             a configuration: `armkit.jit`)


def packed(robot: Robot, gravity: ArrayLike | None = None) -> KernelInertia:
    """The robot's packed dynamics (`Robot.dynamics`), under `gravity` (3,) if given.

    Raises
    ------
    InputError
        If the robot has no inertial parameters.
    """
    d = robot.dynamics
    if d is None:
        raise InputError(f"robot {robot.name}: expected inertial parameters (an inertia: "
                         f"section in its robot file, <inertial> elements in its URDF), found "
                         f"none")
    return d if gravity is None else d.with_gravity(gravity)


VECTOR = (8,)    # the strides of a C-contiguous float64 vector


def _single(a, b, c) -> bool:
    """Whether the three arrays are each of the one type the one-configuration kernels take
    (C-contiguous float64 vectors: strides (8,)); chained comparisons, the cheapest first.
    The kernels check their lengths (and return False to send a wrong one through the checks
    that name it)."""
    return (type(a) is type(b) is type(c) is np.ndarray and a.dtype is b.dtype is c.dtype is FLOAT
            and a.strides == b.strides == c.strides == VECTOR)


def _batch(robot: Robot, **named: ArrayLike) -> tuple[tuple[int, ...], list[NDArray]]:
    """The named joint arrays checked, broadcast to one leading shape and flattened to
    (N, n) each; with that leading shape."""
    arrays = [joint_array(robot, a, name) for name, a in named.items()]
    try:
        lead = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(named, arrays))
        raise InputError(f"{', '.join(named)}: expected shapes that broadcast, found "
                         f"{shapes}") from None
    n = robot.n
    return lead, [np.ascontiguousarray(np.broadcast_to(a, lead + (n,))).reshape(-1, n)
                  for a in arrays]


def inverse_dynamics(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
                     gravity: ArrayLike | None = None) -> NDArray:
    """Joint torques that produce a motion (recursive Newton-Euler).

    Parameters
    ----------
    robot : Robot
        With inertial parameters (`Robot.inertia`).
    q, qd, qdd : array_like, shape (..., n)
        Joint positions (rad, m), velocities (/s) and accelerations (/s^2).
    gravity : array_like, shape (3,), optional
        m/s^2 in the base frame; the robot's own (``(0, 0, -9.80665)`` by default) if None.

    Returns
    -------
    tau : ndarray, shape (..., n)
        N m for revolute, N for prismatic joints: rigid bodies, payload, armature and
        friction.

    Raises
    ------
    InputError
        A robot without inertias; q, qd or qdd of the wrong size, not finite, or with leading
        shapes that do not broadcast.

    Example
    -------
    >>> ur5 = armkit.robot("ur5")
    >>> inverse_dynamics(ur5, np.zeros(6), np.zeros(6), np.zeros(6)).round(2)
    array([  0.  , -53.78, -15.64,   0.  ,   0.  ,   0.  ])
    """
    d = robot.dynamics
    if gravity is None and d is not None and _single(q, qd, qdd):
        tau = np.empty(robot.n)
        if kernels.rnea_one.light(q, qd, qdd, d.floats, d.ints, tau):
            return tau
    d = packed(robot, gravity)
    lead, (Q, QD, QDD) = _batch(robot, q=q, qd=qd, qdd=qdd)
    tau = np.empty(Q.shape)
    core.run(kernels.rnea, kernels.rnea_parallel, Q, QD, QDD, d.floats, d.ints, tau,
             few=LIGHT_CONFIGURATIONS)
    return tau.reshape(lead + (robot.n,))


def gravity_torques(robot: Robot, q: ArrayLike, *,
                    gravity: ArrayLike | None = None) -> NDArray:
    """The torques that hold the arm still against gravity, g(q).

    Parameters
    ----------
    q : array_like, shape (..., n)
    gravity : array_like, shape (3,), optional
        m/s^2 in the base frame; the robot's own if None.

    Returns
    -------
    tau : ndarray, shape (..., n)
        N m, N.
    """
    q = joint_array(robot, q)
    zero = np.zeros(robot.n)
    return inverse_dynamics(robot, q, zero, zero, gravity=gravity)


def coriolis(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray:
    """Coriolis and centrifugal torques C(q, qd) qd (no gravity, friction or armature).

    Parameters
    ----------
    q, qd : array_like, shape (..., n)

    Returns
    -------
    tau : ndarray, shape (..., n)
        N m, N.
    """
    d = packed(robot, np.zeros(3)).without_friction()
    lead, (Q, QD) = _batch(robot, q=q, qd=qd)
    tau = np.empty(Q.shape)
    core.run(kernels.rnea, kernels.rnea_parallel, Q, QD, np.zeros_like(Q), d.floats, d.ints,
             tau, few=LIGHT_CONFIGURATIONS)
    return tau.reshape(lead + (robot.n,))


def mass_matrix(robot: Robot, q: ArrayLike) -> NDArray:
    """Joint-space mass (inertia) matrix M(q), armature on its diagonal (composite rigid body
    algorithm).

    Parameters
    ----------
    q : array_like, shape (..., n)

    Returns
    -------
    M : ndarray, shape (..., n, n)
        Symmetric, positive definite where every joint moves some mass; kg m^2 between two
        revolute joints, kg between two prismatic ones, kg m between one of each.

    Example
    -------
    >>> M = mass_matrix(armkit.robot("ur5"), np.zeros(6))
    >>> bool(np.allclose(M, M.T)), M.shape
    (True, (6, 6))
    """
    d = robot.dynamics
    n = robot.n
    if d is not None and type(q) is np.ndarray and q.dtype is FLOAT and q.strides == VECTOR:
        M = np.empty((n, n))
        if kernels.mass_one.light(q, d.floats, d.ints, M):
            return M
    d = packed(robot)
    q = joint_array(robot, q)
    Q = q.reshape(-1, n)
    M = np.empty((Q.shape[0], n, n))
    core.run(kernels.mass, kernels.mass_parallel, Q, d.floats, d.ints, M,
             few=LIGHT_CONFIGURATIONS)
    return M.reshape(q.shape[:-1] + (n, n))


def coriolis_matrix(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray:
    """The Coriolis matrix C(q, qd): ``C qd`` is `coriolis`, and ``dM/dt - 2 C`` is
    skew-symmetric (the factorisation from the links' Christoffel symbols, as Pinocchio's
    ``computeCoriolisMatrix``).

    Parameters
    ----------
    q, qd : array_like, shape (..., n)

    Returns
    -------
    C : ndarray, shape (..., n, n)
        N m s/rad (N s/m for prismatic joints).
    """
    d = packed(robot)
    lead, (Q, QD) = _batch(robot, q=q, qd=qd)
    n = robot.n
    C = np.empty((Q.shape[0], n, n))
    core.run(kernels.coriolis, kernels.coriolis_parallel, Q, QD, d.floats, d.ints, C,
             few=LIGHT_CONFIGURATIONS)
    return C.reshape(lead + (n, n))


def forward_dynamics(robot: Robot, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, *,
                     gravity: ArrayLike | None = None) -> NDArray:
    """Joint accelerations under given torques: ``M(q)^-1 (tau - C qd - g - friction)``, by
    the composite rigid body algorithm and a Cholesky solve.

    Parameters
    ----------
    q, qd : array_like, shape (..., n)
    tau : array_like, shape (..., n)
        Motor torques, N m and N.
    gravity : array_like, shape (3,), optional
        m/s^2 in the base frame; the robot's own if None.

    Returns
    -------
    qdd : ndarray, shape (..., n)
        rad/s^2 and m/s^2.

    Raises
    ------
    InputError
        As `inverse_dynamics`; and where M(q) is not positive definite (a joint that moves
        no mass and has no armature), naming the first such configuration.
    """
    d = robot.dynamics
    if gravity is None and d is not None and _single(q, qd, tau):
        qdd = np.empty(robot.n)
        if kernels.forward_one.light(q, qd, tau, d.floats, d.ints, qdd):
            return qdd
    d = packed(robot, gravity)
    lead, (Q, QD, TAU) = _batch(robot, q=q, qd=qd, tau=tau)
    qdd = np.empty(Q.shape)
    ok = np.empty(Q.shape[0], dtype=np.bool_)
    core.run(kernels.forward, kernels.forward_parallel, Q, QD, TAU, d.floats, d.ints, qdd, ok,
             few=LIGHT_CONFIGURATIONS)
    if not ok.all():
        bad = int(np.flatnonzero(~ok)[0])
        raise InputError(f"q: expected configurations where the mass matrix is positive "
                         f"definite (every joint moving some mass or armature), found "
                         f"{Q[bad].tolist()} (configuration {bad})")
    return qdd.reshape(lead + (robot.n,))


def with_payload(robot: Robot, mass: float | Inertia | None, com: ArrayLike = (0, 0, 0),
                 tensor: ArrayLike | None = None) -> Robot:
    """The robot holding a payload at its tool (replacing any it had), as a new robot.

    Parameters
    ----------
    mass : float or Inertia or None
        kg; or the payload as an `Inertia` in the tool frame (then com and tensor are not
        given); None or 0 removes the payload.
    com : array_like, shape (3,)
        Its centre of mass in the tool frame (m).
    tensor : array_like, shape (3, 3), optional
        Its rotational inertia about the centre of mass, tool axes (kg m^2); a point mass if
        None.

    Raises
    ------
    InputError
        If the robot has no inertial parameters, or the payload's numbers are invalid.

    Example
    -------
    >>> ur5 = armkit.robot("ur5")
    >>> loaded = with_payload(ur5, 5.0, [0, 0, 0.05])
    >>> loaded.inertia.payload.mass, ur5.inertia.payload
    (5.0, None)
    """
    packed(robot)
    if isinstance(mass, Inertia):
        payload = mass
    elif mass is None or mass == 0:
        payload = None
    else:
        payload = Inertia(mass, com, np.zeros((3, 3)) if tensor is None else tensor)
    return dataclasses.replace(robot, inertia=dataclasses.replace(robot.inertia,
                                                                  payload=payload))

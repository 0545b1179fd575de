"""Jacobians of the tool, their time derivative, tool velocity and acceleration, and measures
of how far a configuration is from a singularity. Batch-first; rows are always
``(vx, vy, vz, wx, wy, wz)``: linear velocity of the tool origin (m/s), then angular velocity
(rad/s).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics import core
from armkit.kinematics.forward import FLOAT, joint_frames
from armkit.model.robot import Robot, joint_array
from armkit.spatial import matrix_to_rpy

Frame = Literal["base", "tool"]
Axes = Literal["all", "trans", "rot"]

STREAM = 1 << 15    # configurations per block when a result is computed block by block


def streamed(compute, q: NDArray, tail: tuple[int, ...]) -> NDArray:
    """``compute(q)`` block by block over the leading axes of `q` (..., n), into one result
    (..., *tail): the temporaries of `compute` (poses, Jacobians, SVDs) stay the size of one
    block, so the peak memory is the result's plus a bounded amount.
    """
    lead = q.shape[:-1]
    flat = q.reshape(-1, q.shape[-1])
    if flat.shape[0] <= STREAM:
        return compute(flat).reshape(lead + tail)
    out = np.empty((flat.shape[0],) + tail)
    for start in range(0, flat.shape[0], STREAM):
        out[start:start + STREAM] = compute(flat[start:start + STREAM])
    return out.reshape(lead + tail)


def pose_and_jacobian(robot: Robot, q: ArrayLike) -> tuple[NDArray, NDArray]:
    """Tool pose (..., 4, 4) and geometric Jacobian in the base frame (..., 6, n), one pass."""
    k = robot.chain.kernel
    if type(q) is np.ndarray and q.dtype is FLOAT and q.shape == robot.chain.lower.shape:
        # One configuration from Python: straight to the kernel, the chain packed in two
        # arrays (as `fk`); the kernel checks finiteness.
        T, J = np.empty((4, 4)), np.empty((6, q.shape[0]))
        if core.pose_jacobian_one.light(q, k.F, k.I, T, J):
            return T, J
    q = joint_array(robot, q)
    flat = q.reshape(-1, robot.n)
    T = np.empty((flat.shape[0], 4, 4))
    J = np.empty((flat.shape[0], 6, robot.n))
    core.run(core.pose_jacobians, core.pose_jacobians_parallel, flat, k.F, k.I, T, J)
    lead = q.shape[:-1]
    return T.reshape(lead + (4, 4)), J.reshape(lead + (6, robot.n))


def _in_tool_frame(T: NDArray, J: NDArray) -> NDArray:
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    return np.concatenate([Rt @ J[..., :3, :], Rt @ J[..., 3:, :]], axis=-2)


def jacobian(robot: Robot, q: ArrayLike, frame: Frame = "base") -> NDArray:
    """Geometric Jacobian of the tool origin.

    Parameters
    ----------
    q : array_like, shape (..., n)
        Joint positions; rad for revolute, m for prismatic joints.
    frame : {"base", "tool"}
        Frame the velocities are expressed in (the point is the tool origin in both).

    Returns
    -------
    J : ndarray, shape (..., 6, n)
        Rows 0-2: linear velocity (m/s); rows 3-5: angular velocity (rad/s), per unit joint rate.

    Raises
    ------
    InputError
        If the last axis of q is not robot.n, or frame is not "base" or "tool".
    """
    if frame == "base":
        chain = robot.chain
        k = chain.kernel
        if (type(q) is np.ndarray and q.dtype is FLOAT and q.shape == chain.lower.shape
                and k.independent):
            # One configuration from Python, as `fk`: J is all the kernel writes.
            J = np.empty((6, q.shape[0]))
            if core.jacobian_one.light(q, k.F, k.I, J):
                return J
        return pose_and_jacobian(robot, q)[1]
    if frame != "tool":
        raise InputError(f"frame: expected 'base' or 'tool', found {frame!r}")
    return streamed(lambda b: _in_tool_frame(*pose_and_jacobian(robot, b)),
                    joint_array(robot, q), (6, robot.n))


def rpy_rate_matrix(rpy: ArrayLike) -> NDArray:
    """E (..., 3, 3) with ``w = E @ d(rpy)/dt`` for ``R = Rz(y) Ry(p) Rx(r)``.

    Columns: the world x axis turned by yaw and pitch, the y axis turned by yaw, and z.
    """
    rpy = np.asarray(rpy, dtype=float)
    p, y = rpy[..., 1], rpy[..., 2]
    cp, sp, cy, sy = np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    E = np.zeros(rpy.shape[:-1] + (3, 3))
    E[..., 0, 0], E[..., 1, 0], E[..., 2, 0] = cy * cp, sy * cp, -sp
    E[..., 0, 1], E[..., 1, 1] = -sy, cy
    E[..., 2, 2] = 1.0
    return E


def jacobian_analytic(robot: Robot, q: ArrayLike) -> NDArray:
    """Analytic Jacobian: tool position and roll-pitch-yaw rates per joint rate.

    Returns
    -------
    Ja : ndarray, shape (..., 6, n)
        Rows 0-2: d(position)/dq (m); rows 3-5: d(roll, pitch, yaw)/dq (rad), base frame, for
        ``R = Rz(yaw) Ry(pitch) Rx(roll)``. At pitch = +-pi/2 the rpy rates do not exist and
        rows 3-5 are NaN.
    """
    return streamed(lambda b: _analytic(*pose_and_jacobian(robot, b)), joint_array(robot, q),
                    (6, robot.n))


def _analytic(T: NDArray, J: NDArray) -> NDArray:
    rpy = matrix_to_rpy(T[..., :3, :3])
    E = rpy_rate_matrix(rpy)
    # det E = cos(pitch); below this the rates are undefined (gimbal lock), not just large.
    singular = np.abs(np.cos(rpy[..., 1])) < 1e-12
    E[singular] = np.eye(3)
    rates = np.linalg.solve(E, J[..., 3:, :])
    rates[singular] = np.nan
    return np.concatenate([J[..., :3, :], rates], axis=-2)


def jacobian_dot(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray:
    """Time derivative of the base-frame geometric Jacobian along joint velocity qd.

    Parameters
    ----------
    q, qd : array_like, shape (..., n)
        Joint positions and velocities (rad/s, m/s); leading shapes broadcast.

    Returns
    -------
    Jd : ndarray, shape (..., 6, n)

    Notes
    -----
    Joint i's axis z_i and point o_i are fixed in link i-1, which turns at w_{i-1}, so
    ``dz_i/dt = w_{i-1} x z_i`` and ``do_i/dt`` is the velocity of that link at o_i. Then a
    revolute column ``(z x (p - o), z)`` has derivative
    ``(dz x (p - o) + z x (dp - do), dz)`` and a prismatic column ``(z, 0)`` has ``(dz, 0)``.
    """
    q, qd = np.broadcast_arrays(joint_array(robot, q), joint_array(robot, qd, "qd"))
    both = np.concatenate([q, qd], axis=-1)         # one array to stream block by block
    n = robot.n
    return streamed(lambda b: _jacobian_dot(robot, b[:, :n], b[:, n:]), both, (6, n))


def _jacobian_dot(robot: Robot, q: NDArray, qd: NDArray) -> NDArray:
    chain = robot.chain
    moved, T = joint_frames(robot, q)
    z, o, p = moved[..., :3, 2], moved[..., :3, 3], T[..., :3, 3]
    revolute = chain.kernel.kinds == 0                  # per moving joint, mimic ones included
    if chain.coupled:
        qd = qd @ chain.coupling.T
    w = np.zeros(q.shape[:-1] + (3,))             # angular velocity of the current link
    ref, v_ref = o[..., 0, :], np.zeros_like(w)   # a point of that link and its velocity
    dz, do = np.empty_like(z), np.empty_like(o)
    for i in range(chain.n_joints):
        dz[..., i, :] = np.cross(w, z[..., i, :])
        do[..., i, :] = v_ref + np.cross(w, o[..., i, :] - ref)
        rate = qd[..., i, None]
        if revolute[i]:
            w = w + z[..., i, :] * rate
            v_ref = do[..., i, :]
        else:
            v_ref = do[..., i, :] + z[..., i, :] * rate
        ref = o[..., i, :]
    dp = v_ref + np.cross(w, p - ref)
    r = revolute[:, None]
    linear = np.where(r, np.cross(dz, p[..., None, :] - o) + np.cross(z, dp[..., None, :] - do),
                      dz)
    angular = np.where(r, dz, 0.0)
    Jdot = np.concatenate([np.swapaxes(linear, -1, -2), np.swapaxes(angular, -1, -2)], axis=-2)
    return Jdot @ chain.coupling if chain.coupled else Jdot


def tool_velocity(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray:
    """Tool twist ``J qd`` (..., 6) in the base frame: linear (m/s), then angular (rad/s)."""
    q, qd = np.broadcast_arrays(joint_array(robot, q), joint_array(robot, qd, "qd"))
    n = robot.n
    return streamed(lambda b: (jacobian(robot, b[:, :n]) @ b[:, n:, None])[..., 0],
                    np.concatenate([q, qd], axis=-1), (6,))


def tool_acceleration(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> NDArray:
    """Tool acceleration ``J qdd + Jdot qd`` (..., 6), base frame: m/s^2, then rad/s^2.

    The linear part is the acceleration of the tool origin; the angular part the angular
    acceleration of the tool.
    """
    q, qd, qdd = np.broadcast_arrays(joint_array(robot, q), joint_array(robot, qd, "qd"),
                                     joint_array(robot, qdd, "qdd"))
    n = robot.n

    def block(b: NDArray) -> NDArray:
        q, qd, qdd = b[:, :n], b[:, n:2 * n], b[:, 2 * n:]
        J, Jd = jacobian(robot, q), _jacobian_dot(robot, q, qd)
        return (J @ qdd[..., None] + Jd @ qd[..., None])[..., 0]

    return streamed(block, np.concatenate([q, qd, qdd], axis=-1), (6,))


# --- distance from singularities -------------------------------------------------------------

def _rows(axes: Axes | ArrayLike) -> NDArray:
    named = {"all": np.ones(6, bool), "trans": np.r_[True, True, True, False, False, False],
             "rot": np.r_[False, False, False, True, True, True]}
    if isinstance(axes, str):
        if axes not in named:
            raise InputError(f"axes: expected 'all', 'trans', 'rot' or 6 booleans, found {axes!r}")
        return named[axes]
    mask = np.asarray(axes, dtype=bool)
    if mask.shape != (6,) or not mask.any():
        raise InputError(f"axes: expected 6 booleans (x y z rx ry rz), not all false, "
                         f"found {np.asarray(axes).tolist()}")
    return mask


def singular_values(robot: Robot, q: ArrayLike, axes: Axes | ArrayLike = "all") -> NDArray:
    """Singular values of the base-frame Jacobian's chosen rows, largest first.

    Parameters
    ----------
    axes : {"all", "trans", "rot"} or array_like of 6 bool
        Which task rows count: all six, the linear ones, the angular ones, or a mask over
        ``(x, y, z, rx, ry, rz)``.

    Returns
    -------
    s : ndarray, shape (..., min(rows, n))
    """
    rows = _rows(axes)
    return streamed(lambda b: _singular_values(robot, b, rows), joint_array(robot, q),
                    (min(int(rows.sum()), robot.n),))


def _singular_values(robot: Robot, q: NDArray, rows: NDArray) -> NDArray:
    return np.linalg.svd(pose_and_jacobian(robot, q)[1][..., rows, :], compute_uv=False)


def _measure(robot: Robot, q: ArrayLike, axes, reduce) -> NDArray:
    """``reduce(singular values)`` (..., ) block by block: only the result is kept whole."""
    rows = _rows(axes)
    return streamed(lambda b: reduce(_singular_values(robot, b, rows)), joint_array(robot, q),
                    ())


def manipulability(robot: Robot, q: ArrayLike, axes: Axes | ArrayLike = "all") -> NDArray:
    """Yoshikawa's manipulability: the product of the Jacobian's singular values, (...,).

    Equal to ``sqrt(det(J J^T))`` when the chosen rows are no more than the joints, and to
    ``sqrt(det(J^T J))`` otherwise (an arm with fewer than six joints), so it is zero exactly
    at a singularity in both cases.
    """
    return _measure(robot, q, axes, lambda s: np.prod(s, axis=-1))


def min_singular_value(robot: Robot, q: ArrayLike, axes: Axes | ArrayLike = "all") -> NDArray:
    """Smallest singular value of the chosen Jacobian rows, (...,); zero at a singularity."""
    return _measure(robot, q, axes, lambda s: s[..., -1])


def condition_number(robot: Robot, q: ArrayLike, axes: Axes | ArrayLike = "all") -> NDArray:
    """Largest over smallest singular value, (...,); inf at a singularity."""
    def ratio(s: NDArray) -> NDArray:
        with np.errstate(divide="ignore"):
            return s[..., 0] / s[..., -1]

    return _measure(robot, q, axes, ratio)

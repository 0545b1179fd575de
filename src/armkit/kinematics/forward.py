"""Forward kinematics: the tool pose and every link frame, batch-first."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.kinematics import core
from armkit.model.robot import Robot, joint_array

FLOAT = np.dtype(np.float64)   # the one dtype the one-configuration path hands to the kernels


def fk(robot: Robot, q: ArrayLike) -> NDArray:
    """Tool pose in the robot's base (world) frame.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)
        Joint positions; rad for revolute, m for prismatic joints.

    Returns
    -------
    T : ndarray, shape (..., 4, 4)
        ``T_base_tool`` for each configuration.

    Raises
    ------
    InputError
        If the last axis of q is not robot.n, or q holds NaN or inf.

    Example
    -------
    >>> armkit.fk(armkit.robot("ur5"), np.zeros(6))[:3, 3]
    array([-0.81725 , -0.19145 , -0.005491])
    """
    chain = robot.chain
    k = chain.kernel
    if type(q) is np.ndarray and q.dtype is FLOAT and q.shape == chain.lower.shape:
        # One configuration from Python: straight to the kernel, the chain packed in two
        # arrays (what numba's dispatcher costs grows with the arrays passed); the kernel also
        # checks finiteness (a non-finite q falls through to joint_array, which says what is
        # wrong).
        out = np.empty((4, 4))
        if core.pose_one.light(q, k.F, k.I, out):
            return out
    q = joint_array(robot, q)
    flat = q.reshape(-1, robot.n)
    out = np.empty((flat.shape[0], 4, 4))
    core.run(core.poses, core.poses_parallel, flat, k.F, k.I, out,
                 few=core.LIGHT_POSES)
    return out.reshape(q.shape[:-1] + (4, 4))


def joint_frames(robot: Robot, q: ArrayLike) -> tuple[NDArray, NDArray]:
    """Each moving joint's frame after its motion, whose z axis is the joint axis, and the
    tool pose.

    Returns
    -------
    frames : ndarray, shape (..., n_joints, 4, 4)
        n_joints is ``robot.chain.n_joints``: robot.n, and any mimic joints.
    T : ndarray, shape (..., 4, 4)
    """
    q = joint_array(robot, q)
    flat = q.reshape(-1, robot.n)
    n = robot.chain.n_joints
    frames = np.empty((flat.shape[0], n, 4, 4))
    out = np.empty((flat.shape[0], 4, 4))
    k = robot.chain.kernel
    core.run(core.frames, core.frames_parallel, flat, k.F, k.I, frames,
                 out)
    lead = q.shape[:-1]
    return frames.reshape(lead + (n, 4, 4)), out.reshape(lead + (4, 4))


def fk_frames(robot: Robot, q: ArrayLike) -> NDArray:
    """Every link frame: the base, then the frame after each joint (the tool pose last).

    Parameters
    ----------
    q : array_like, shape (..., n)

    Returns
    -------
    frames : ndarray, shape (..., n_joints + 1, 4, 4)
        ``frames[..., 0]`` is ``T_base``; ``frames[..., i]`` is link frame i (for DH tables the
        DH frame of moving joint i, with any fixed rows right after it; for URDF the child link
        of moving joint i, mimic joints counted); ``frames[..., -1]`` is the tool pose.
    """
    moved, T = joint_frames(robot, q)
    lead, n = T.shape[:-2], robot.chain.n_joints
    out = np.empty(lead + (n + 1, 4, 4))
    out[..., 0, :, :] = robot.chain.T_base
    out[..., 1:n, :, :] = moved[..., :-1, :, :] @ robot.chain.kernel.after
    out[..., n, :, :] = T
    return out

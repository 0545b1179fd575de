"""Straight-line tool motion: the line sampled at a stated step, followed by inverse kinematics
from one sample to the next, stopping where the arm cannot follow instead of jumping.

Positions move along the segment at a constant rate and the orientation turns about one fixed
axis (slerp, ``R(s) = R0 exp(s log(R0^T R1))``). Each sample's IK starts from the previous
sample's solution, with no restart (a restart could land on another branch: a jump). The line
ends early, with its reason, at the first sample that

- is not solved within the tolerances from the previous one: the line leaves the workspace
  ("out of reach": full IK finds no configuration either), a joint limit stops it ("outside
  joint limits"), or the pose is reachable only on another branch ("singular");
- needs a joint step far larger than the Cartesian step explains: the arm passes near a
  singularity, where joint speeds grow without bound ("singular").

The reasons are those of `armkit.kinematics.ik.reasons`; the following is
`IKSolver.track`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics.forward import fk
from armkit.kinematics.ik import IKSolver
from armkit.kinematics.ik.reasons import OUT_OF_REACH, OUTSIDE_JOINT_LIMITS, SINGULAR
from armkit.kinematics.ik.masks import as_mask, mask_name, task_errors
from armkit.model.robot import Robot, joint_array
from armkit.spatial import as_transform, exp_so3, log_so3, rotation_angle


@dataclass(frozen=True)
class CartesianPath:
    """Straight-line tool motion as joint samples.

    Attributes
    ----------
    s : ndarray, shape (K,)
        Path parameter of each sample, 0 at the start, 1 at the goal.
    poses : ndarray, shape (K, 4, 4)
        The tool poses wanted along the line.
    q : ndarray, shape (k, n)
        Joint solutions of the samples followed (k <= K; k == K when the whole line is).
    position_error, rotation_error : ndarray, shape (k,)
        m and rad, by forward kinematics of q.
    success : bool
        The whole line was followed.
    reason : str
        "ok", "out of reach" (no configuration reaches the next pose), "outside joint limits"
        (a joint limit stops the line), or "singular" (the next pose needs another branch:
        the arm would jump).
    stop : float
        Path parameter (0..1) of the last sample followed: 1.0 exactly on success; 0.0 when
        only the start was followed, or not even the start (then q has no row).
    mask : str
        The task followed.
    """

    s: NDArray
    poses: NDArray
    q: NDArray
    position_error: NDArray
    rotation_error: NDArray
    success: bool
    reason: str
    stop: float
    mask: str


def line_poses(T_start: ArrayLike, T_goal: ArrayLike, s: ArrayLike) -> NDArray:
    """Poses (K, 4, 4) at s (K,) along the straight line from T_start to T_goal, slerped."""
    T0, T1 = np.asarray(T_start, dtype=float), np.asarray(T_goal, dtype=float)
    s = np.asarray(s, dtype=float)
    out = np.zeros(s.shape + (4, 4))
    out[..., :3, :3] = T0[:3, :3] @ exp_so3(s[..., None] * log_so3(T0[:3, :3].T @ T1[:3, :3]))
    out[..., :3, 3] = T0[:3, 3] + s[..., None] * (T1[:3, 3] - T0[:3, 3])
    out[..., 3, 3] = 1.0
    return out


def cartesian_line(robot: Robot, T_start: ArrayLike, T_goal: ArrayLike, q0: ArrayLike, *,
                   step: float = 0.005, angle_step: float = np.deg2rad(1.0),
                   mask: str | ArrayLike | None = None, tol_position: float = 1e-9,
                   tol_rotation: float = 1e-9, max_iter: int = 50,
                   max_joint_step: float | None = None) -> CartesianPath:
    """Follow the straight line from T_start to T_goal with the tool, from configuration q0.

    Parameters
    ----------
    robot : Robot
    T_start, T_goal : array_like, shape (4, 4)
        Tool poses at the two ends (base frame, m).
    q0 : array_like, shape (n,)
        A configuration at (or near) T_start: it picks the branch the line is followed on.
    step : float
        Largest distance between samples along the line, m.
    angle_step : float
        Largest turn between samples, rad.
    mask : str or 6 flags, optional
        The task followed (see `armkit.ik`); the robot's default if omitted.
    tol_position, tol_rotation : float
        Each sample's tolerances, m and rad.
    max_iter : int
        IK iterations per sample.
    max_joint_step : float, optional
        Largest change of any joint between samples before the line counts as crossing a
        singularity: rad for revolute joints, m for prismatic ones. Default 0.35 (20 deg),
        about ten times what a sample of 5 mm moves a well-conditioned arm of a metre.

    Returns
    -------
    CartesianPath
        The samples followed; `success` False with the reason and the place it stopped if the
        arm cannot follow the whole line.

    Raises
    ------
    InputError
        Bad poses, q0, steps or mask.
    """
    T0, T1 = as_transform(T_start, "T_start"), as_transform(T_goal, "T_goal")
    if T0.shape != (4, 4) or T1.shape != (4, 4):
        raise InputError(f"T_start, T_goal: expected one pose each (4, 4), found {T0.shape} "
                         f"and {T1.shape}")
    q0 = joint_array(robot, q0, "q0")
    if q0.shape != (robot.n,):
        raise InputError(f"q0: expected one configuration ({robot.n},), found {q0.shape}")
    max_joint_step = 0.35 if max_joint_step is None else max_joint_step
    for name, value in (("step", step), ("angle_step", angle_step),
                        ("max_joint_step", max_joint_step)):
        if not value > 0:
            raise InputError(f"{name}: expected a positive step, found {value}")
    solver = IKSolver(robot, samples=0)
    mask = solver.default_mask if mask is None else as_mask(mask)
    length = np.linalg.norm(T1[:3, 3] - T0[:3, 3])
    turn_angle = float(rotation_angle(T0[:3, :3].T @ T1[:3, :3]))
    K = int(max(np.ceil(length / step), np.ceil(turn_angle / angle_step), 1)) + 1
    s = np.linspace(0.0, 1.0, K)
    poses = line_poses(T0, T1, s)
    followed = solver.track(poses, q0, mask=mask, tol_position=tol_position,
                            tol_rotation=tol_rotation, max_iter=max_iter,
                            max_joint_step=max_joint_step)
    q, k = followed.q, followed.followed
    pe, re = task_errors(fk(robot, q), poses[:k], mask)
    if followed.success or followed.reason == SINGULAR:
        reason = followed.reason
    else:
        # Not solved from the previous sample: ask full IK (every branch, restarts) whether the
        # pose can be reached at all. If it can, the line needs another branch here: the arm
        # would have to jump across a singularity, or a joint limit is in the way.
        last = q[-1] if k else q0
        whole = solver.solve(poses[k], last, mask=mask, tol_position=tol_position,
                             tol_rotation=tol_rotation)
        if whole.reason in (OUT_OF_REACH, OUTSIDE_JOINT_LIMITS):
            reason = whole.reason
        else:
            chain = robot.chain
            turn = chain.wraps
            at_limit = np.any(~turn & ((last <= chain.lower + 1e-9)
                                       | (last >= chain.upper - 1e-9)))
            reason = OUTSIDE_JOINT_LIMITS if at_limit else SINGULAR
    return CartesianPath(s, poses, q, pe, re, followed.success, reason,
                         float(s[k - 1]) if k else 0.0, mask_name(mask))

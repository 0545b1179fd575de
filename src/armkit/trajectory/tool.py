"""The tool's motion along a joint trajectory: its path, velocity and acceleration.

``xd = J qd`` and ``xdd = J qdd + Jdot qd`` (SPEC.md section 2), through `armkit.fk`,
`armkit.tool_velocity` and `armkit.tool_acceleration`, batch over the samples; the tool-changer
paper's figure 9 plots them for its Table 1 case.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armkit.errors import InputError
from armkit.kinematics import fk, tool_acceleration, tool_velocity
from armkit.model.robot import Robot
from armkit.trajectory.piecewise import Samples, Trajectory


@dataclass(frozen=True)
class ToolMotion:
    """The tool along a trajectory, base frame, SI.

    Attributes
    ----------
    t : ndarray, shape (N,)
        s.
    pose : ndarray, shape (N, 4, 4)
        ``T_base_tool``.
    velocity : ndarray, shape (N, 6)
        ``J qd``: linear velocity of the tool origin (m/s), then angular velocity (rad/s).
    acceleration : ndarray, shape (N, 6)
        ``J qdd + Jdot qd``: linear (m/s^2), then angular (rad/s^2).
    """

    t: NDArray
    pose: NDArray
    velocity: NDArray
    acceleration: NDArray

    @property
    def position(self) -> NDArray:
        """Tool origin (N, 3), m."""
        return self.pose[..., :3, 3]

    @property
    def speed(self) -> NDArray:
        """|linear velocity| (N,), m/s."""
        return np.linalg.norm(self.velocity[..., :3], axis=-1)

    @property
    def path_length(self) -> float:
        """Length of the sampled tool path (m), summed over the samples' chords."""
        return float(np.linalg.norm(np.diff(self.position, axis=0), axis=-1).sum())


def tool_motion(robot: Robot, motion: Trajectory | Samples, t: ArrayLike | None = None, *,
                count: int = 500) -> ToolMotion:
    """Tool pose, velocity and acceleration along a joint trajectory.

    Parameters
    ----------
    robot : Robot
    motion : Trajectory or Samples
        Joint motion over all of the robot's joints (SI).
    t : array_like, shape (N,), optional
        Sample times (s) for a Trajectory; default `count` evenly spaced from start to end.
        Ignored for Samples, which carry their own.

    Returns
    -------
    ToolMotion

    Raises
    ------
    InputError
        If the motion's joint count is not the robot's.
    """
    if isinstance(motion, Trajectory):
        motion = motion.sample(np.linspace(motion.start, motion.end, count) if t is None else t)
    if motion.q.shape[-1] != robot.n:
        raise InputError(f"motion: expected {robot.n} joints (the joints of {robot.name}), "
                         f"found {motion.q.shape[-1]}")
    return ToolMotion(np.asarray(motion.t), fk(robot, motion.q),
                      tool_velocity(robot, motion.q, motion.qd),
                      tool_acceleration(robot, motion.q, motion.qd, motion.qdd))

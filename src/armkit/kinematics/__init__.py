"""What a robot does, as pure functions of (robot, q): forward kinematics and Jacobians.

The Jacobian itself is `armkit.jacobian` (defined in `armkit.kinematics.jacobian`); it is not
re-exported here, so that ``armkit.kinematics.jacobian`` stays the module.
"""

from armkit.kinematics.forward import fk, fk_frames, joint_frames
from armkit.kinematics.jacobian import (condition_number, jacobian_analytic, jacobian_dot,
                                        manipulability, min_singular_value, pose_and_jacobian,
                                        singular_values, tool_acceleration, tool_velocity)

__all__ = ["fk", "fk_frames", "joint_frames", "jacobian_analytic", "jacobian_dot",
           "pose_and_jacobian", "tool_velocity", "tool_acceleration", "singular_values",
           "manipulability", "min_singular_value", "condition_number"]

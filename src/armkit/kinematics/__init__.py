"""What a robot does, as pure functions of (robot, q): forward kinematics and Jacobians.

The Jacobian itself is `armkit.jacobian` (defined in `armkit.kinematics.jacobian`); it is not
re-exported here, so that ``armkit.kinematics.jacobian`` stays the module.
"""

from armkit.kinematics.forward import fk, fk_frames, joint_frames
from armkit.kinematics.jacobian import (condition_number, jacobian_analytic, jacobian_dot,
                                        manipulability, min_singular_value, pose_and_jacobian,
                                        singular_values, tool_acceleration, tool_velocity)
from armkit.lazy import public_names

__all__ = public_names(__name__)

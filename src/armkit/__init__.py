"""armkit: serial robot arms from a parameter table to moving drives.

SI units inside (m, rad, s); batch-first NumPy arrays, ``q`` of shape ``(..., n)``.

>>> import armkit
>>> ur5 = armkit.robot("ur5")
>>> armkit.fk(ur5, [0, -1.57, 1.57, 0, 0, 0]).shape
(4, 4)
"""

from armkit.errors import ArmkitError, DriveError, InputError, ModelFileError
from armkit.kinematics import (condition_number, fk, fk_frames, jacobian, jacobian_analytic,
                               jacobian_dot, manipulability, min_singular_value,
                               singular_values, tool_acceleration, tool_velocity)
from armkit.model import Robot, load_robot, robot, robots, save_robot
from armkit.workspace import Section, Workspace, workspace

__version__ = "0.1.0"

__all__ = ["ArmkitError", "InputError", "ModelFileError", "DriveError", "Robot", "robot",
           "robots", "load_robot", "save_robot", "fk", "fk_frames", "jacobian",
           "jacobian_analytic", "jacobian_dot", "tool_velocity", "tool_acceleration",
           "singular_values", "manipulability", "min_singular_value", "condition_number",
           "workspace", "Workspace", "Section"]

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
from armkit.kinematics.ik import IKResult, IKSolutions, ik, ik_solutions
from armkit.model import Robot, load_robot, robot, robots, save_robot
from armkit.trajectory import (Trajectory, cubic, jerk_limited, quintic, retime, spline,
                               tool_motion, trapezoidal)
from armkit.workspace import Section, Workspace, workspace
from armkit.planning import PlanResult, Scene, plan

# Loaded on first use, so that `import armkit` does not pay for pymodbus (about 0.1 s).
_DRIVES = ("load_register_map", "check_waypoints", "send_waypoints", "DriveClient", "SimDrive")


def __getattr__(name: str):
    if name in _DRIVES:
        import armkit.drives
        return getattr(armkit.drives, name)
    raise AttributeError(f"module 'armkit' has no attribute {name!r}")


__version__ = "0.1.0"

__all__ = ["ArmkitError", "InputError", "ModelFileError", "DriveError", "Robot", "robot",
           "robots", "load_robot", "save_robot", "fk", "fk_frames", "jacobian",
           "jacobian_analytic", "jacobian_dot", "tool_velocity", "tool_acceleration",
           "singular_values", "manipulability", "min_singular_value", "condition_number",
           "ik", "ik_solutions", "IKResult", "IKSolutions", "Trajectory", "cubic", "quintic",
           "trapezoidal", "jerk_limited", "spline", "retime", "tool_motion", "workspace",
           "Workspace", "Section", "plan", "PlanResult", "Scene", *_DRIVES]

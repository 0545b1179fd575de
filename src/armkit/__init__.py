"""armkit: serial robot arms from a parameter table to moving drives.

SI units inside (m, rad, s); batch-first NumPy arrays, ``q`` of shape ``(..., n)``.

>>> import armkit
>>> ur5 = armkit.robot("ur5")
>>> armkit.fk(ur5, [0, -1.57, 1.57, 0, 0, 0]).shape
(4, 4)

Every name below is loaded on first use (PEP 562), so that ``import armkit`` costs little
more than NumPy: numba, scipy, pydantic, matplotlib, pymodbus and dask are imported only by
the calls that need them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from armkit.errors import ArmkitError, DriveError, InputError, ModelFileError
from armkit.lazy import lazy_names

if TYPE_CHECKING:       # the public names, each loaded at its first use (armkit.lazy)
    from armkit.calibration import (AccuracyReport, CalibrationResult, CameraMount,
                                    HandEyeResult, accuracy_report, calibrate, handeye,
                                    points_to_base, poses_to_base, select_poses)
    from armkit.drives import DriveClient, SimDrive, check_waypoints, send_waypoints
    from armkit.dynamics import (TorqueLimits, coriolis, coriolis_matrix, forward_dynamics,
                                 gravity_torques, inverse_dynamics, mass_matrix,
                                 torque_profile, with_payload)
    from armkit.io.register_maps import load_register_map
    from armkit.io.camera import read_camera_mount
    from armkit.perception import TargetResult, detect_target
    from armkit.planning import PlanResult, Scene, plan
    from armkit.reach import Orientations, Placement, ReachMap, base_placement, reach_map
    from armkit.kinematics.forward import fk, fk_frames
    from armkit.kinematics.ik import IKResult, IKSolutions, IKSolver, IKTrack, ik, ik_solutions
    from armkit.kinematics.jacobian import (condition_number, jacobian, jacobian_analytic,
                                            jacobian_dot, manipulability, min_singular_value,
                                            singular_values, tool_acceleration, tool_velocity)
    from armkit.io.robot_files import load_robot, robot, robots, save_robot
    from armkit.io.tasks import Task, demo_task, load_task
    from armkit.job import JobResult, run_job
    from armkit.report.view import show
    from armkit.model.robot import Robot
    from armkit.sampled_workspace import Section, Workspace, workspace
    from armkit.threads import get_num_threads, set_num_threads
    from armkit.trajectory import (RetimeResult, Trajectory, cubic, jerk_limited, quintic,
                                   retime, retime_jerk, spline, tool_motion, trapezoidal)
    from armkit.warmup import warm_up


__getattr__, __dir__, __all__ = lazy_names(__name__)


__version__ = "0.1.0"


"""The end-to-end job of SPEC.md section 8, as far as it is built, on built-in defaults.

Paper 1's water-supply system: a camera sees the train's water inlet; the target goes to the
arm's base frame, inverse kinematics finds every solution and the one nearest the arm's current
configuration, a smooth joint trajectory (the 10-15-6 quintic at the shortest duration within
the joint limits) goes there, and its waypoints go to the drives over Modbus TCP: here a
simulated drive, a real Modbus TCP server on loopback.

Not built yet (listed in `NOT_BUILT`): collision-free planning around obstacles, hand-eye and
kinematic calibration, task files (``armkit run TASK.yaml``) and the HTML report.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from armkit.kinematics.ik import IKResult, IKSolutions, IKSolver
from armkit.model import Robot, robot as load
from armkit.spatial import pose_from_xyz_rpy
from armkit.trajectory import Trajectory, quintic

if TYPE_CHECKING:
    from armkit.drives import SendResult

NOT_BUILT = ("collision-free planning around obstacles (SPEC 5)",
             "hand-eye and kinematic calibration (SPEC 6)",
             "task files, armkit run TASK.yaml, and the HTML report (SPEC 8)")


@dataclass(frozen=True)
class DemoTask:
    """The built-in job: the water-supply arm, a camera over it, an inlet it sees (SI)."""

    robot: str = "water_supply"
    # The camera, 2.2 m up beside the arm, looking straight down (its z axis along -z).
    T_base_camera: NDArray = field(default_factory=lambda: pose_from_xyz_rpy(
        [0.6, -0.2, 2.2], [np.pi, 0.0, np.pi / 2]))
    # The inlet as the camera reports it (in the base frame: 1.0, 0.3, 0.8 m, yaw 30 deg).
    target_in_camera: NDArray = field(default_factory=lambda: pose_from_xyz_rpy(
        [0.5, 0.4, 1.4], np.deg2rad([180.0, 0.0, 60.0])))
    q_current: NDArray = field(default_factory=lambda: np.array([0.05, 0.0, 0.5, -0.5]))
    waypoints: int = 10                  # paper 1 sends 10 waypoints to the motors
    drive_map: str = "water_supply.map.yaml"


@dataclass(frozen=True)
class DemoReport:
    """What each built step of the job produced (SI)."""

    robot: Robot
    task: DemoTask
    T_base_target: NDArray               # (4, 4)
    solutions: IKSolutions
    ik: IKResult
    trajectory: Trajectory | None
    t: NDArray                           # (N,) s, waypoint times
    q: NDArray                           # (N, n) waypoints
    sent: SendResult | None
    figures: tuple[Path, ...]
    not_built: tuple[str, ...] = NOT_BUILT


def run_demo(out: Path | None = None, task: DemoTask | None = None) -> DemoReport:
    """Run the job on the built-in task; write its figures to `out` if given.

    Returns
    -------
    DemoReport
        A failed IK shows in ``report.ik.success`` and ``reason``; then no motion is sent
        (``report.sent`` is None).
    """
    from armkit.drives import SimDrive, load_register_map, send_waypoints

    task = task or DemoTask()
    robot = load(task.robot)
    T_target = task.T_base_camera @ task.target_in_camera
    solver = IKSolver(robot)
    solutions = solver.solutions(T_target)
    result = solver.solve(T_target, task.q_current)
    if not result.success:
        return DemoReport(robot, task, T_target, solutions, result, None, np.empty(0),
                          np.empty((0, robot.n)), None, ())
    chain = robot.chain
    trajectory = quintic(task.q_current, result.q, vmax=chain.velocity_limits,
                         amax=chain.acceleration_limits)
    t = np.linspace(0.0, trajectory.duration, task.waypoints)
    q = trajectory.evaluate(t)
    with resources.as_file(resources.files("armkit.drives") / task.drive_map) as path:
        drive_map = load_register_map(path)
    with SimDrive(drive_map) as drive:
        sent = send_waypoints(drive_map, q, t, port=drive.port)
    figures = () if out is None else _figures(robot, trajectory, Path(out))
    return DemoReport(robot, task, T_target, solutions, result, trajectory, t, q, sent, figures)


def _figures(robot: Robot, trajectory: Trajectory, out: Path) -> tuple[Path, ...]:
    from armkit.report.trajectory import motion_figure, tool_figure
    from armkit.trajectory import tool_motion

    out.mkdir(parents=True, exist_ok=True)
    paths = (out / "demo_joint_motion.png", out / "demo_tool_motion.png")
    motion_figure(robot, trajectory).savefig(paths[0], dpi=90)
    samples = trajectory.sample_uniform(400)
    tool_figure(robot, {"quintic": tool_motion(robot, samples)}).savefig(paths[1], dpi=90)
    return paths

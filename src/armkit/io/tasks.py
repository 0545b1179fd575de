"""Task files: the end-to-end job of SPEC.md section 8 as one YAML file, in its declared units,
read into a `Task` (SI) made of one record per capability: what the job is asked to do.
`armkit.job.run_job` does it; io never imports the job.

::

    name: fill the tender's tank
    units: {length: mm, angle: deg}
    robot: water_supply                  # a built-in name, or a robot file next to the task
    camera: {xyz: [600, -200, 2200], rpy: [180, 0, 90]}    # the camera's pose in the base frame
    target: {xyz: [500, 400, 1400], rpy: [180, 0, 60]}     # the target as the camera sees it
    start: [0, 0, 0, 0]                  # where the simulated drive starts (joint values)
    scene:                               # obstacles in the base frame (and/or file: FILE)
      obstacles:                         # as in scene files (armkit.io.scene)
        - {type: box, name: pillar, xyz: [900, 0, 800], size: [120, 120, 1600]}
    planner: {name: rrtconnect, seed: 1, time_limit: 5, resolution: 5}
    motion: {waypoints: 10, speed: 1.0}  # paper 1 sends 10 waypoints to the motors
    drive: {host: 192.0.2.10, port: 502, map: drive.map.yaml}   # omitted: the simulated drive
    report: task-report                  # the report's folder (the CLI's --out wins)

``camera`` may instead name a file: a camera-to-base file or a hand-eye result
(`armkit.io.camera`); an eye-in-hand result also needs the joints the arm had when the camera
measured (``camera: {file: handeye.yaml, q: [...]}``). ``target`` may instead be a point cloud of
the inlet, read with the task and searched by `armkit.perception.detect_target` when the job
runs::

    target: {cloud: scan.pcd, kind: pipe, radius: 40, mask: position}

``mask`` names what inverse kinematics must match (default: the robot's own; ``position`` for
a cloud). File names (robot, camera, cloud, scene, drive map, report) are relative to the task
file's folder; a robot name follows `armkit.io.robot_files.robot`'s rule.

Every mistake is one `ModelFileError`: file, field path, what was expected, what was found,
with "did you mean" for a misspelled key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from armkit.calibration import camera_to_base
from armkit.drives.registers import RegisterMap
from armkit.errors import ModelFileError
from armkit.io.camera import read_camera_mount
from armkit.io.clouds import Cloud, read_cloud
from armkit.io.documents import (SEED, Positive, StrictModel, UnitsField, Value, bounded,
                                 read_yaml, validated, whole)
from armkit.io.register_maps import builtin_register_map, load_register_map
from armkit.io.robot_files import MAX_LENGTH, robot_named_in
from armkit.io.scene import Obstacle, obstacle_from_field, read_scene
from armkit.kinematics.forward import fk
from armkit.kinematics.ik.masks import NAMED_MASKS
from armkit.model.chain import freeze
from armkit.model.robot import Robot, Units
from armkit.planning.scene import Scene
from armkit.spatial import pose_from_xyz_rpy

Vector3 = Annotated[list[Value], Field(min_length=3, max_length=3)]


# --- what a task is ------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class PoseTarget:
    """The target as the camera reports it.

    Attributes
    ----------
    T_camera_target : ndarray, (4, 4)
        m.
    mask : str or None
        What inverse kinematics must match (`armkit.kinematics.ik.masks.NAMED_MASKS`); None:
        the robot's own.
    """

    T_camera_target: NDArray
    mask: str | None = None

    def __post_init__(self):
        freeze(self, "T_camera_target")


@dataclass(frozen=True, eq=False)
class CloudTarget:
    """The target to be found in a point cloud of the inlet (`armkit.perception.detect_target`).

    Attributes
    ----------
    cloud : armkit.io.clouds.Cloud
        Points in the sensor (camera) frame, m.
    kind : {"pipe", "hole"}
    radius : float or None
        The inlet's radius (m), or None to fit it.
    mask : str or None
        What inverse kinematics must match; ``"position"`` by default (a cloud gives no yaw).
    """

    cloud: Cloud
    kind: Literal["pipe", "hole"] = "pipe"
    radius: float | None = None
    mask: str | None = "position"


@dataclass(frozen=True)
class PlannerSettings:
    """How the path is planned (`armkit.planning.plan`) and checked.

    Attributes
    ----------
    name : {"rrtconnect", "rrt", "rrtstar"}
    seed : int
    time_limit : float
        s.
    max_iterations : int or None
    resolution : float
        m: the most any point of the arm moves between two checked states.
    radius : float or None
        m: the radius of the default link capsules when the robot file declares none.
    """

    name: str = "rrtconnect"
    seed: int = 0
    time_limit: float = 5.0
    max_iterations: int | None = None
    resolution: float = 0.005
    radius: float | None = None


@dataclass(frozen=True)
class MotionSettings:
    """The motion sent to the drive.

    Attributes
    ----------
    waypoints : int
        Waypoints sent (paper 1: 10).
    speed : float
        Fraction of the joint velocity, acceleration and jerk limits the motion may use, (0, 1].
    """

    waypoints: int = 10
    speed: float = 1.0


@dataclass(frozen=True, eq=False)
class DriveSettings:
    """The drive the waypoints go to.

    Attributes
    ----------
    register_map : armkit.drives.RegisterMap
    host : str or None
        None: the built-in simulated drive, on an ephemeral loopback port for the job's length.
    port : int
    timeout : float
        s, per request.
    arrival_timeout : float
        s, the longest wait for the drive to report the last waypoint reached.
    """

    register_map: RegisterMap
    host: str | None = None
    port: int = 502
    timeout: float = 1.0
    arrival_timeout: float = 30.0


@dataclass(frozen=True, eq=False)
class Task:
    """One job, SI: built by `load_task` from a task file, or in code.

    Attributes
    ----------
    name : str
    robot : Robot
    units : Units
        The task file's, for what the job prints and reports.
    T_base_camera : ndarray, (4, 4)
        The camera's (or sensor's) pose in the base frame, m.
    target : PoseTarget or CloudTarget
    drive : DriveSettings
    start : ndarray (n,) or None
        Where the simulated drive starts (a real drive reports where the arm is).
    scene : armkit.planning.Scene
    planner : PlannerSettings
    motion : MotionSettings
    report : Path or None
        The report's folder.
    """

    name: str
    robot: Robot
    units: Units
    T_base_camera: NDArray
    target: PoseTarget | CloudTarget
    drive: DriveSettings
    start: NDArray | None = None
    scene: Scene = field(default_factory=Scene)
    planner: PlannerSettings = PlannerSettings()
    motion: MotionSettings = MotionSettings()
    report: Path | None = None

    def __post_init__(self):
        freeze(self, "T_base_camera", "start")


# --- the file ------------------------------------------------------------------------------

class CameraField(StrictModel):
    """The camera's pose in the base frame, or a file: a camera-to-base file or a hand-eye
    result (`armkit.io.camera`); an eye-in-hand camera also needs the joints it measured at."""

    xyz: Vector3 | None = None
    rpy: Vector3 = [0.0, 0.0, 0.0]
    file: str | None = None
    q: list[Value] | None = None


class TargetField(StrictModel):
    xyz: Vector3 | None = None
    rpy: Vector3 | None = None
    yaw: Value | None = None
    cloud: str | None = None            # a point cloud of the inlet (armkit.io.clouds)
    kind: Literal["pipe", "hole"] = "pipe"
    radius: Positive | None = None                     # the inlet's, length units; else fitted
    cloud_units: Literal["mm", "m"] | None = None     # when the cloud file declares none
    mask: str | None = None             # the IK task: position, position+yaw, pose, ...


class SceneField(StrictModel):
    file: str | None = None             # a scene file (.yaml or MoveIt's .scene), relative
    obstacles: list[Obstacle] = []      # as in scene files (`armkit.io.scene`)


class PlannerField(StrictModel):
    name: Literal["rrtconnect", "rrt", "rrtstar"] = "rrtconnect"
    seed: whole(*SEED) = 0
    time_limit: bounded(0.0, 3600.0, low_open=True) = 5.0
    max_iterations: whole(1, 10_000_000) | None = None
    resolution: Positive | None = None               # length units: how far any arm point moves
    radius: Positive | None = None                   # default link capsules' radius, length units


class MotionField(StrictModel):
    waypoints: whole(2, 10_000) = 10
    speed: bounded(0.0, 1.0, low_open=True) = 1.0             # fraction of the joint limits


class DriveField(StrictModel):
    host: str = "127.0.0.1"
    port: whole(1, 65535) = 502
    map: str | None = None
    timeout: bounded(0.0, 60.0, low_open=True) = 1.0
    arrival_timeout: bounded(0.0, 3600.0, low_open=True) = 30.0


class TaskFile(StrictModel):
    name: str = ""
    description: str = ""
    units: UnitsField
    robot: str
    camera: CameraField | None = None
    target: TargetField
    start: list[Value] | None = None
    scene: SceneField | None = None
    planner: PlannerField = PlannerField()
    motion: MotionField = MotionField()
    drive: DriveField | None = None
    report: str | None = None


def load_task(path: str | Path) -> Task:
    """Read and validate a task file into a `Task` (SI).

    Raises
    ------
    ModelFileError
        Unreadable file, bad YAML, or any field that is wrong (file, field, expected, found),
        in the task file or in a file it names (robot, camera, cloud, scene, register map).
    """
    return parse_task(read_yaml(path), path)


def demo_task() -> Task:
    """The built-in task of `armkit demo`: paper 1's water-supply arm, a camera over the track
    that sees the inlet, and a post between the arm's rest pose and the inlet."""
    with resources.as_file(resources.files("armkit") / "tasks" / "water_supply.task.yaml") as p:
        return load_task(p)


def parse_task(document: Any, path: str | Path = "<task>") -> Task:
    """A `Task` (SI) from a parsed task document; relative file names are taken from the
    task file's folder.

    Raises
    ------
    ModelFileError
        For any mistake: file, field, expected, found.
    """
    where = str(path)
    if not isinstance(document, dict):
        raise ModelFileError(where, "top level", "a mapping of task fields",
                             "nothing" if document is None else type(document).__name__)
    spec = validated(where, document, TaskFile)
    folder = Path(path).parent if where != "<task>" else Path(".")
    units = Units(spec.units.length, spec.units.angle)
    if spec.camera is None:
        raise ModelFileError(where, "camera", "the camera's pose in the base frame "
                             "({xyz, rpy}) or a camera file ({file})", "nothing")
    robot = robot_named_in(where, spec.robot)
    p = spec.planner
    return Task(
        name=spec.name or Path(where).stem, robot=robot, units=units,
        T_base_camera=_camera(spec.camera, robot, units, folder, where),
        target=_target(spec.target, units, folder, where),
        drive=_drive(spec.drive, robot, folder, where),
        start=None if spec.start is None else _start(spec.start, robot, units, where),
        scene=_scene(spec.scene, units, folder), planner=PlannerSettings(
            p.name, p.seed, p.time_limit, p.max_iterations,
            0.005 if p.resolution is None else float(units.length_to_si(p.resolution)),
            None if p.radius is None else float(units.length_to_si(p.radius))),
        motion=MotionSettings(spec.motion.waypoints, spec.motion.speed),
        report=None if spec.report is None else folder / spec.report)


def _camera(spec: CameraField, robot: Robot, units: Units, folder: Path,
            where: str) -> NDArray:
    """T_base_camera from a pose, or from a camera file (a fixed mount or a hand-eye result)."""
    if (spec.xyz is None) == (spec.file is None):
        raise ModelFileError(where, "camera", "a pose (xyz, rpy) or a file, one of them",
                             "both" if spec.file else "neither")
    if spec.file is None:
        if spec.q is not None:
            raise ModelFileError(where, "camera.q", "joint values only with an eye-in-hand "
                                 "hand-eye result file", "a fixed camera pose")
        return _pose(spec.xyz, spec.rpy, units, where, "camera")
    mount = read_camera_mount(folder / spec.file)
    if mount.kind != "eye_in_hand":
        if spec.q is not None:
            raise ModelFileError(where, "camera.q", f"no joint values for a {mount.kind} "
                                 "camera (it does not move with the arm)", "some")
        return camera_to_base(mount)
    if spec.q is None or len(spec.q) != robot.n:
        raise ModelFileError(where, "camera.q", f"the {robot.n} joint values the arm had when "
                             "the camera (on its gripper) measured", "none" if spec.q is None
                             else f"{len(spec.q)}")
    return camera_to_base(mount, fk(robot, _joint_si(spec.q, robot, units)))


def _target(target: TargetField, units: Units, folder: Path,
            where: str) -> PoseTarget | CloudTarget:
    mask = target.mask
    if mask is not None and mask not in NAMED_MASKS:
        raise ModelFileError(where, "target.mask", f"one of {', '.join(NAMED_MASKS)}",
                             repr(mask))
    if target.cloud is not None:
        if any(v is not None for v in (target.xyz, target.rpy, target.yaw)):
            raise ModelFileError(where, "target", "a cloud or a pose (xyz, rpy or yaw), not "
                                 "both", "both")
        radius = None if target.radius is None else float(units.length_to_si(target.radius))
        return CloudTarget(read_cloud(folder / target.cloud, target.cloud_units), target.kind,
                           radius, mask or "position")
    if target.xyz is None:
        raise ModelFileError(where, "target.xyz", "the target's position as the camera sees "
                             "it (or cloud: FILE)", "nothing")
    if target.rpy is not None and target.yaw is not None:
        raise ModelFileError(where, "target", "rpy or yaw, not both", "both")
    rpy = target.rpy if target.rpy is not None else [0.0, 0.0, target.yaw or 0.0]
    return PoseTarget(_pose(target.xyz, rpy, units, where, "target"), mask)


def _start(values: list[float], robot: Robot, units: Units, where: str) -> NDArray:
    if len(values) != robot.n:
        raise ModelFileError(where, "start", f"{robot.n} joint values for {robot.name}",
                             f"{len(values)}")
    start = _joint_si(values, robot, units)
    outside = (start < robot.lower - 1e-12) | (start > robot.upper + 1e-12)
    if outside.any():
        j = int(np.flatnonzero(outside)[0])
        raise ModelFileError(where, f"start[{j}]", f"a value within {robot.joint_names[j]}'s "
                             "limits", f"{values[j]:g}")
    return start


def _drive(spec: DriveField | None, robot: Robot, folder: Path, where: str) -> DriveSettings:
    if spec is None:
        return DriveSettings(builtin_register_map(robot))
    if spec.map is None:
        raise ModelFileError(where, "drive.map", "the drive's register map file", "nothing")
    return DriveSettings(load_register_map(folder / spec.map, robot), spec.host, spec.port,
                         spec.timeout, spec.arrival_timeout)


def _joint_si(values: list[float], robot: Robot, units: Units) -> NDArray:
    q = np.asarray(values, dtype=float)
    return np.where(robot.chain.revolute, units.angle_to_si(q), units.length_to_si(q))


def _pose(xyz, rpy, units: Units, where: str, name: str) -> NDArray:
    p = units.length_to_si(xyz)
    if np.any(np.abs(p) > MAX_LENGTH):
        raise ModelFileError(where, f"{name}.xyz", f"lengths within {MAX_LENGTH:g} m",
                             f"{np.max(np.abs(p)):g} m")
    return pose_from_xyz_rpy(p, units.angle_to_si(rpy))


def _scene(spec: SceneField | None, units: Units, folder: Path) -> Scene:
    if spec is None:
        return Scene()
    inline = Scene(tuple(obstacle_from_field(o, units) for o in spec.obstacles))
    return inline if spec.file is None else read_scene(folder / spec.file) + inline

"""Task files: the end-to-end job of SPEC.md section 8 as one YAML file, in its declared units.

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
the inlet, found by `armkit.perception.detect_target` when the job runs::

    target: {cloud: scan.pcd, kind: pipe, radius: 40, mask: position}

``mask`` names the IK task (default: the robot's own; ``position`` for a cloud).

Every mistake is one `ModelFileError`: file, field path, what was expected, what was found,
with "did you mean" for a misspelled key.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field

from armkit.errors import ArmkitError, ModelFileError
from armkit.io.documents import (SEED, Positive, StrictModel, UnitsField, Value, bounded,
                                 read_yaml, validated, whole)
from armkit.io.scene import Obstacle
from armkit.io.robot_files import MAX_LENGTH
from armkit.model.robot import Units
from armkit.spatial import pose_from_xyz_rpy

Vector3 = Annotated[list[Value], Field(min_length=3, max_length=3)]


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


def parse_task(document: Any, path: str | Path = "<task>"):
    """A `Task` (SI) from a parsed task document; relative file names are taken from the
    task file's folder.

    Raises
    ------
    ModelFileError
        For any mistake: file, field, expected, found.
    """
    from armkit.task import Task  # the job's own object; io only reads files into it

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
    robot = _robot(spec.robot, folder, where)
    T_base_camera = _camera(spec.camera, robot, units, folder, where)
    target, cloud, mask = spec.target, None, _mask(spec.target.mask, where)
    if target.cloud is not None:
        if any(v is not None for v in (target.xyz, target.rpy, target.yaw)):
            raise ModelFileError(where, "target", "a cloud or a pose (xyz, rpy or yaw), not "
                                 "both", "both")
        cloud = {"path": folder / target.cloud, "kind": target.kind,
                 "radius": None if target.radius is None else float(
                     units.length_to_si(target.radius)), "units": target.cloud_units}
        T_camera_target = None
        mask = mask or "position"
    else:
        if target.xyz is None:
            raise ModelFileError(where, "target.xyz", "the target's position as the camera "
                                 "sees it (or cloud: FILE)", "nothing")
        if target.rpy is not None and target.yaw is not None:
            raise ModelFileError(where, "target", "rpy or yaw, not both", "both")
        rpy = target.rpy if target.rpy is not None else [0.0, 0.0, target.yaw or 0.0]
        T_camera_target = _pose(target.xyz, rpy, units, where, "target")
    start = None
    if spec.start is not None:
        if len(spec.start) != robot.n:
            raise ModelFileError(where, "start", f"{robot.n} joint values for {robot.name}",
                                 f"{len(spec.start)}")
        start = _joint_si(spec.start, robot, units)
        outside = (start < robot.lower - 1e-12) | (start > robot.upper + 1e-12)
        if outside.any():
            j = int(np.flatnonzero(outside)[0])
            raise ModelFileError(where, f"start[{j}]", f"a value within {robot.joint_names[j]}'s "
                                 "limits", f"{spec.start[j]:g}")
    scene = _scene(spec.scene, units, folder, where)
    p = spec.planner
    drive = spec.drive
    drive_map = None
    if drive is not None and drive.map is not None:
        drive_map = _register_map(folder / drive.map, robot, where)
    elif drive is not None:
        raise ModelFileError(where, "drive.map", "the drive's register map file", "nothing")
    return Task(
        name=spec.name or Path(where).stem, robot=robot, units=units,
        T_base_camera=T_base_camera, T_camera_target=T_camera_target, target_cloud=cloud,
        mask=mask, start=start, scene=scene, planner=p.name, seed=p.seed,
        time_limit=p.time_limit, max_iterations=p.max_iterations,
        resolution=None if p.resolution is None else float(units.length_to_si(p.resolution)),
        radius=None if p.radius is None else float(units.length_to_si(p.radius)),
        waypoints=spec.motion.waypoints, speed=spec.motion.speed,
        drive_host=None if drive is None else drive.host,
        drive_port=None if drive is None else drive.port,
        drive_map=drive_map, drive_timeout=1.0 if drive is None else drive.timeout,
        arrival_timeout=30.0 if drive is None else drive.arrival_timeout,
        report=None if spec.report is None else folder / spec.report)


def load_task(path: str | Path):
    """Read and validate a task file into a `Task` (SI).

    Raises
    ------
    ModelFileError
        Unreadable file, bad YAML, or any field that is wrong (file, field, expected, found).
    """
    return parse_task(read_yaml(path), path)


def _robot(name: str, folder: Path, where: str):
    from armkit.io.robot_files import robot, robots

    try:
        if name in robots():
            return robot(name)
        return robot(folder / name)
    except ModelFileError:
        raise
    except ArmkitError as err:
        raise ModelFileError(where, "robot", "a built-in robot name or a robot file",
                             f"{name!r} ({err})") from None


def _camera(spec: CameraField, robot, units: Units, folder: Path, where: str) -> np.ndarray:
    """T_base_camera from a pose, or from a camera file (a fixed mount or a hand-eye result)."""
    from armkit.calibration import camera_to_base
    from armkit.io.camera import read_camera_mount

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
    from armkit.kinematics import fk
    return camera_to_base(mount, fk(robot, _joint_si(spec.q, robot, units)))


def _mask(name: str | None, where: str) -> str | None:
    from armkit.kinematics.ik.task import NAMED_MASKS

    if name is not None and name not in NAMED_MASKS:
        raise ModelFileError(where, "target.mask", f"one of {', '.join(NAMED_MASKS)}",
                             repr(name))
    return name


def _joint_si(values: list[float], robot, units: Units) -> np.ndarray:
    q = np.asarray(values, dtype=float)
    revolute = np.asarray(robot.chain.revolute)
    return np.where(revolute, units.angle_to_si(q), units.length_to_si(q))


def _length(x, units: Units, where: str, field: str):
    v = units.length_to_si(x)
    if np.any(np.abs(v) > MAX_LENGTH):
        raise ModelFileError(where, field, f"lengths within {MAX_LENGTH:g} m",
                             f"{np.max(np.abs(v)):g} m")
    return v


def _pose(xyz, rpy, units: Units, where: str, field: str) -> np.ndarray:
    return pose_from_xyz_rpy(_length(xyz, units, where, f"{field}.xyz"),
                             units.angle_to_si(rpy))


def _scene(spec, units: Units, folder: Path, where: str):
    from armkit.io.scene import obstacle_from_field, read_scene
    from armkit.planning import Scene

    if spec is None:
        return Scene()
    inline = Scene(tuple(obstacle_from_field(o, units) for o in spec.obstacles))
    return inline if spec.file is None else read_scene(folder / spec.file) + inline


def _register_map(path: Path, robot, where: str):
    from armkit.drives import load_register_map

    return load_register_map(path, robot)

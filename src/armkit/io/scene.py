"""Scene and planning files: obstacles in YAML (file units), MoveIt's ``.scene`` text format, and
the planning problem `armkit plan` reads.

A scene or planning file (YAML)::

    units: {length: mm, angle: deg}
    robot: inspection_6dof          # built-in name or robot file (relative to this file)
    radius: 40                      # optional: the default capsules, this radius
    obstacles:
      - {type: box, min: [650, -500, 200], max: [1100, 500, 240], name: lower plate}
      - {type: box, size: [100, 100, 100], xyz: [500, 0, 0], rpy: [0, 0, 45]}
      - {type: sphere, center: [400, 300, 200], radius: 80}
      - {type: cylinder, radius: 50, length: 400, xyz: [0, 600, 200], rpy: [0, 0, 0]}
      - {type: capsule, a: [0, 0, 0], b: [0, 0, 300], radius: 40}
    scene: cell.scene               # optional: obstacles from a MoveIt scene file (metres)
    start: [31.9, -91, 77.6, -135.9, 127.1, -141.1]
    goal: [-50.2, -23.3, -77.5, 96.9, -53.4, 131.7]   # or goal_pose: {xyz: [...], rpy: [...]}
    planner: {name: rrtconnect, seed: 0, resolution: 5, waypoints: 10}

Cylinders and capsules of a pose lie along its z axis; ``rpy`` is roll-pitch-yaw about the fixed
x, y, z axes. A MoveIt ``.scene`` file holds boxes, spheres and cylinders with positions (m) and
quaternions (x, y, z, w), in either the old layout (shapes right after ``* name``) or the newer
one (an object pose first). Every mistake is one ModelFileError naming the file and the field
(for ``.scene`` files, the line).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from armkit.errors import ModelFileError
from armkit.io.documents import (SEED, Fraction, Positive, StrictModel, UnitsField, Value,
                                 bounded, checked_path, found_text, number_from_text, read_text,
                                 read_yaml, validated, whole)
from armkit.io.robot_files import robot_named_in
from armkit.model.robot import Robot, Units
from armkit.planning.scene import Box, Capsule, Cylinder, Scene, Sphere
from armkit.spatial import pose_from_xyz_rpy, quat_to_matrix

Vector3 = Annotated[list[Value], Field(min_length=3, max_length=3)]
MAX_OBSTACLES = 100_000         # obstacles in one file, and shapes of one MoveIt object
MAX_NAME = 200                  # characters of an obstacle's name
Name = Annotated[str, Field(max_length=MAX_NAME)]


class _BoxField(StrictModel):
    type: Literal["box"]
    name: Name = ""
    min: Vector3 | None = None
    max: Vector3 | None = None
    size: Annotated[list[Positive], Field(min_length=3, max_length=3)] | None = None
    xyz: Vector3 = [0.0, 0.0, 0.0]
    rpy: Vector3 = [0.0, 0.0, 0.0]

    @model_validator(mode="after")
    def _one_form(self):
        corners = self.min is not None and self.max is not None
        if corners == (self.size is not None) or (self.min is None) != (self.max is None):
            raise ValueError("expected either min and max corners or size (with xyz, rpy), "
                             "found " + ("both" if corners else "neither"))
        if corners and not all(b > a for a, b in zip(self.min, self.max)):
            raise ValueError(f"expected max above min on every axis, found min {self.min} and "
                             f"max {self.max}")
        return self


class _SphereField(StrictModel):
    type: Literal["sphere"]
    name: Name = ""
    center: Vector3
    radius: Positive


class _CylinderField(StrictModel):
    type: Literal["cylinder"]
    name: Name = ""
    radius: Positive
    length: Positive
    xyz: Vector3 = [0.0, 0.0, 0.0]
    rpy: Vector3 = [0.0, 0.0, 0.0]


class _CapsuleField(StrictModel):
    type: Literal["capsule"]
    name: Name = ""
    a: Vector3
    b: Vector3
    radius: Positive


Obstacle = Annotated[_BoxField | _SphereField | _CylinderField | _CapsuleField,
                     Field(discriminator="type")]


class _PoseField(StrictModel):
    xyz: Vector3
    rpy: Vector3 = [0.0, 0.0, 0.0]


class _PlannerField(StrictModel):
    name: Literal["rrtconnect", "rrt", "rrtstar"] = "rrtconnect"
    seed: whole(*SEED) = 0
    resolution: Positive | None = None
    step: Positive | None = None
    max_iterations: whole(1, 100_000_000) | None = None
    time_limit: bounded(0.0, 3600.0, low_open=True) = 10.0
    goal_bias: Fraction = 0.05
    waypoints: whole(2, 100_000) | None = None
    simplify: bool = Field(True, strict=True)


class _SceneFile(StrictModel):
    units: UnitsField
    robot: str | None = None
    radius: Positive | None = None
    obstacles: Annotated[list[Obstacle], Field(max_length=MAX_OBSTACLES)] = []
    scene: str | None = None
    start: list[Value] | None = None
    goal: list[Value] | list[list[Value]] | None = None
    goal_pose: _PoseField | None = None
    planner: _PlannerField = _PlannerField()


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """A planning file, in SI: what `armkit.planning.plan` needs, and the file's units.

    robot may be None (a scene file without one); start, goal (k, n), goal_pose (4, 4) may be
    None; settings are `plan`'s keyword arguments (planner, seed, resolution, ...).
    """

    path: str
    units: Units
    scene: Scene
    robot: Robot | None = None
    radius: float | None = None
    start: np.ndarray | None = None
    goal: np.ndarray | None = None
    goal_pose: np.ndarray | None = None
    settings: dict = field(default_factory=dict)


def obstacle_from_field(o, units: Units):
    """An obstacle of a validated file (`Obstacle` field, file units) in SI."""
    length, angle = units.length_to_si, units.angle_to_si
    if isinstance(o, _BoxField):
        if o.size is None:
            return Box.from_bounds(length(o.min), length(o.max), o.name)
        return Box(length(o.size), pose_from_xyz_rpy(length(o.xyz), angle(o.rpy)), o.name)
    if isinstance(o, _SphereField):
        return Sphere(length(o.center), float(length(o.radius)), o.name)
    if isinstance(o, _CylinderField):
        return Cylinder(float(length(o.radius)), float(length(o.length)),
                        pose_from_xyz_rpy(length(o.xyz), angle(o.rpy)), o.name)
    return Capsule(length(o.a), length(o.b), float(length(o.radius)), o.name)


def read_scene(path: str | Path) -> Scene:
    """The obstacles of a scene or planning file (.yaml) or a MoveIt scene file (.scene).

    Raises
    ------
    ModelFileError
    """
    if str(path).lower().endswith(".scene"):
        return read_moveit_scene(path)
    return read_planning_problem(path, need_robot=False).scene


def read_planning_problem(path: str | Path, need_robot: bool = True) -> PlanningProblem:
    """A planning file (see the module's note) in SI.

    Raises
    ------
    ModelFileError
        Naming the file and the field; a robot that does not load, joint lists of the wrong
        length, and a missing start or goal (with need_robot) included.
    """
    path = str(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping of fields (units, obstacles, ...)",
                             type(document).__name__)
    spec = validated(path, document, _SceneFile)
    if spec.goal is not None and spec.goal_pose is not None:
        raise ModelFileError(path, "goal_pose", "either goal or goal_pose", "both")
    units = Units(spec.units.length, spec.units.angle)
    obstacles = [obstacle_from_field(o, units) for o in spec.obstacles]
    if spec.scene is not None:
        moveit = checked_path(spec.scene, path, "scene", Path(path).parent)
        if not moveit.is_file():
            raise ModelFileError(path, "scene", "a MoveIt scene file (its path relative to "
                                 "this file)", f"{found_text(spec.scene)}, which is not a file")
        obstacles += list(read_moveit_scene(moveit))
    scene = Scene(obstacles)
    robot = None
    if spec.robot is not None:
        robot = robot_named_in(path, spec.robot)
    elif need_robot:
        raise ModelFileError(path, "robot", "a built-in robot name or a robot file", "nothing")
    settings = spec.planner.model_dump()
    settings["planner"] = settings.pop("name")
    if settings["resolution"] is not None:
        settings["resolution"] = float(units.length_to_si(settings["resolution"]))
    settings = {k: v for k, v in settings.items() if v is not None}
    start = goal = goal_pose = None
    if robot is not None:
        if spec.start is not None:
            start = _joints(robot, spec.start, units, path, "start")
        elif need_robot:
            raise ModelFileError(path, "start", f"{robot.n} joint values", "nothing")
        if spec.goal is not None:
            rows = spec.goal if spec.goal and isinstance(spec.goal[0], list) else [spec.goal]
            goal = np.array([_joints(robot, g, units, path, "goal") for g in rows])
        elif spec.goal_pose is not None:
            goal_pose = pose_from_xyz_rpy(units.length_to_si(spec.goal_pose.xyz),
                                          units.angle_to_si(spec.goal_pose.rpy))
        elif need_robot:
            raise ModelFileError(path, "goal", "joint values or a goal_pose", "nothing")
    radius = None if spec.radius is None else float(units.length_to_si(spec.radius))
    return PlanningProblem(path, units, scene, robot, radius, start, goal, goal_pose, settings)


def _joints(robot: Robot, values: list[float], units: Units, path: str, name: str) -> np.ndarray:
    if len(values) != robot.n:
        raise ModelFileError(path, name, f"{robot.n} joint values (the joints of {robot.name})",
                             f"{len(values)}")
    v = np.asarray(values, dtype=float)
    return np.where(robot.chain.revolute, units.angle_to_si(v), units.length_to_si(v))


# --- MoveIt .scene ------------------------------------------------------------------------------

class _Lines:
    def __init__(self, path: str):
        self.path = path
        self.lines = [(i + 1, line.strip()) for i, line in enumerate(read_text(path).splitlines())
                      if line.strip()]
        self.i = 0

    def peek(self) -> tuple[int, str]:
        return self.lines[self.i] if self.i < len(self.lines) else (len(self.lines) + 1, "")

    def next(self, what: str) -> tuple[int, str]:
        number, line = self.peek()
        if not line:
            raise ModelFileError(self.path, f"line {number}", what, "the end of the file")
        self.i += 1
        return number, line

    def numbers(self, count: int, what: str) -> np.ndarray:
        number, line = self.next(what)
        words = line.split()
        if len(words) != count:
            raise ModelFileError(self.path, f"line {number}", what, found_text(line))
        try:
            return np.array([number_from_text(w, self.path, "") for w in words])
        except ModelFileError as err:
            raise ModelFileError(self.path, f"line {number}", f"{what}, each {err.expected}",
                                 err.found) from None

    def count(self, what: str, most: int, least: int = 1) -> int:
        number, line = self.next(what)
        try:
            return number_from_text(line, self.path, "", least, most, integer=True)
        except ModelFileError as err:
            raise ModelFileError(self.path, f"line {number}", f"{what}: {err.expected}",
                                 err.found) from None


def _pose(lines: _Lines) -> np.ndarray:
    p = lines.numbers(3, "a position x y z (m)")
    q = lines.numbers(4, "an orientation quaternion x y z w")
    if not np.linalg.norm(q) > 1e-9:
        raise ModelFileError(lines.path, f"line {lines.peek()[0] - 1}",
                             "a non-zero quaternion", "0 0 0 0")
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(q / np.linalg.norm(q))
    T[:3, 3] = p
    return T


def read_moveit_scene(path: str | Path) -> Scene:
    """Boxes, spheres and cylinders of a MoveIt planning scene text file (.scene), metres.

    Raises
    ------
    ModelFileError
        Naming the line: what was expected (a shape type, three numbers, ...) and what came.
    """
    lines = _Lines(str(path))
    lines.next("a scene name")
    obstacles = []
    while True:
        number, line = lines.next("'* object name' or '.' to end")
        if line == ".":
            break
        if not line.startswith("*"):
            raise ModelFileError(lines.path, f"line {number}", "'* object name' or '.'",
                                 repr(line))
        name = line[1:].strip()
        if len(name) > MAX_NAME:
            raise ModelFileError(lines.path, f"line {number}", f"an object name of at most "
                                 f"{MAX_NAME} characters", f"{len(name)} characters")
        T_object = np.eye(4)
        newer = len(lines.peek()[1].split()) == 3            # the newer layout: an object pose
        if newer:
            T_object = _pose(lines)
        for _ in range(lines.count("the number of shapes", MAX_OBSTACLES)):
            number, kind = lines.next("a shape type (box, sphere, cylinder)")
            if kind == "box":
                dims = lines.numbers(3, "box sizes x y z (m)")
            elif kind == "sphere":
                dims = lines.numbers(1, "a sphere radius (m)")
            elif kind == "cylinder":
                dims = lines.numbers(2, "a cylinder radius and length (m)")
            else:
                raise ModelFileError(lines.path, f"line {number}",
                                     "a shape type armkit reads (box, sphere, cylinder)",
                                     repr(kind))
            if not np.all(dims > 0):
                raise ModelFileError(lines.path, f"line {number + 1}", "positive sizes",
                                     " ".join(f"{d:g}" for d in dims))
            T = T_object @ _pose(lines)
            lines.numbers(4, "a colour r g b a")
            if kind == "box":
                obstacles.append(Box(dims, T, name))
            elif kind == "sphere":
                obstacles.append(Sphere(T[:3, 3], dims[0], name))
            else:
                obstacles.append(Cylinder(dims[0], dims[1], T, name))
        if newer and lines.peek()[1].isascii() and lines.peek()[1].isdigit():
            # subframes (named poses): skipped
            for _ in range(lines.count("the number of subframes", MAX_OBSTACLES, 0)):
                lines.next("a subframe name")
                _pose(lines)
    return Scene(obstacles)


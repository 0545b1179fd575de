"""Task-pose files: the poses a robot must reach, in the world, and where its base may stand
(`armkit place`), YAML in the file's declared units.

::

    units: {length: m, angle: deg}
    poses:                               # the task, in the world frame
      - {name: stop 1, xyz: [1.20, 0.90, 0.80], rpy: [0, 0, -90]}
      - {name: stop 2, xyz: [1.35, 0.90, 0.80], yaw: -90}      # rpy [0, 0, yaw]
    base:                                # where the base frame may stand: a floor ...
      floor: {x: [-0.5, 0.5], y: [-0.5, 0.5], z: 0, step: 0.05, yaw_step: 10}
    # ... or a rail:  base: {rail: {from: [0, 0, 0], to: [3, 0, 0], step: 0.01, yaw: 90}}
    mask: position+yaw                   # optional: the IK task (default: the map's, else the
                                         # robot's own)
    criterion: reachability              # optional: or manipulability

A floor's ``yaw`` is a range ``[low, high]`` (default one turn) every ``yaw_step`` (default 10
deg); a rail's ``yaw`` is one angle (default 0) or a range. Every mistake is one
`ModelFileError` naming the file and the field.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from armkit.errors import InputError, ModelFileError
from armkit.io.documents import Number, StrictModel, UnitsField, kind_of, read_yaml, validated
from armkit.kinematics.ik.masks import NAMED_MASKS
from armkit.model.robot import Units
from armkit.reach.placement import SCORES, BaseGrid, floor_grid, rail_grid
from armkit.spatial import pose_from_xyz_rpy

MOST_POSES = 10_000
COORDINATE = 1e9            # file units, as the command line's
Vector3 = Annotated[list[Number], Field(min_length=3, max_length=3)]
Range = Annotated[list[Number], Field(min_length=2, max_length=2)]


class _PoseField(StrictModel):
    name: str = ""
    xyz: Vector3
    rpy: Vector3 | None = None
    yaw: Number | None = None

    @model_validator(mode="after")
    def _one_orientation(self):
        if self.rpy is not None and self.yaw is not None:
            raise ValueError("expected rpy or yaw, found both")
        return self


class _FloorField(StrictModel):
    x: Range
    y: Range
    z: Number = 0.0
    step: Number
    yaw: Range | None = None
    yaw_step: Number = 10.0


class _RailField(StrictModel):
    from_: Vector3 = Field(alias="from")
    to: Vector3
    step: Number
    yaw: Number | Range = 0.0
    yaw_step: Number = 10.0


class _BaseField(StrictModel):
    floor: _FloorField | None = None
    rail: _RailField | None = None

    @model_validator(mode="after")
    def _one_kind(self):
        if (self.floor is None) == (self.rail is None):
            raise ValueError("expected floor or rail, found "
                             + ("both" if self.floor is not None else "neither"))
        return self


class _TaskPosesFile(StrictModel):
    units: UnitsField
    poses: Annotated[list[_PoseField], Field(min_length=1, max_length=MOST_POSES)]
    base: _BaseField
    mask: Literal[tuple(NAMED_MASKS)] | None = None
    criterion: Literal[SCORES] | None = None


@dataclass(frozen=True, eq=False)
class TaskPoses:
    """A task-pose file in SI: the poses (P, 4, 4) in the world, their names, the base grid,
    and the IK task and score it asks for (None: the defaults)."""

    path: str
    units: Units
    poses: np.ndarray
    names: tuple[str, ...]
    grid: BaseGrid
    mask: str | None
    criterion: str | None


def read_task_poses(path: str | Path) -> TaskPoses:
    """The task-pose file at `path` (see the module's note).

    Raises
    ------
    ModelFileError
        Naming the file and the field: not YAML, a field missing, unknown or of the wrong
        kind, a number out of range, or a base grid too large.
    """
    path = str(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping of fields (units, poses, base, ...)",
                             kind_of(document))
    spec = validated(path, document, _TaskPosesFile)
    units = Units(spec.units.length, spec.units.angle)
    length, angle = units.length_to_si, units.angle_to_si
    poses, names = [], []
    for i, pose in enumerate(spec.poses):
        _coordinates(path, f"poses[{i}].xyz", pose.xyz)
        rpy = pose.rpy if pose.rpy is not None else [0.0, 0.0, pose.yaw or 0.0]
        _coordinates(path, f"poses[{i}].{'yaw' if pose.yaw is not None else 'rpy'}", rpy)
        poses.append(pose_from_xyz_rpy(length(pose.xyz), angle(rpy)))
        names.append(pose.name or f"pose {i}")
    try:
        if spec.base.floor is not None:
            where, f = "base.floor", spec.base.floor
            for name in ("x", "y"):
                _coordinates(path, f"{where}.{name}", getattr(f, name))
            _coordinates(path, f"{where}.z", [f.z])
            grid = floor_grid(tuple(length(f.x)), tuple(length(f.y)), float(length(f.step)),
                              z=float(length(f.z)),
                              yaw=None if f.yaw is None else tuple(angle(f.yaw)),
                              yaw_step=float(angle(f.yaw_step)))
        else:
            where, r = "base.rail", spec.base.rail
            _coordinates(path, f"{where}.from", r.from_)
            _coordinates(path, f"{where}.to", r.to)
            yaw = (float(angle(r.yaw)) if not isinstance(r.yaw, list)
                   else tuple(angle(r.yaw)))
            grid = rail_grid(length(r.from_), length(r.to), float(length(r.step)), yaw=yaw,
                             yaw_step=float(angle(r.yaw_step)))
    except InputError as err:
        field, _, rest = str(err).partition(": ")
        expected, _, found = rest.removeprefix("expected ").partition(", found ")
        field = {"rail": "step", "start, end": "from"}.get(field, field)
        raise ModelFileError(path, f"{where}.{field}", expected, found or "another value") \
            from None
    return TaskPoses(path, units, np.array(poses), tuple(names), grid, spec.mask,
                     spec.criterion)


def _coordinates(path: str, field: str, values) -> None:
    """Coordinates within COORDINATE file units, as the command line takes them."""
    for v in values:
        if not abs(v) <= COORDINATE:
            raise ModelFileError(path, field, f"numbers from {-COORDINATE:g} to {COORDINATE:g}",
                                 f"{v:g}")

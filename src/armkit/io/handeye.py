"""Hand-eye files: the pose pairs a calibration starts from, and the result it writes.

A poses file (YAML) gives, per measurement, the gripper's pose (or the joint values of a named
robot) and the target's pose as the camera saw it, in the file's units::

    units: {length: mm, angle: deg}
    mode: eye_in_hand            # eye_in_hand (camera on the gripper) | eye_to_hand
    robot: water_supply          # optional: only when poses give joint values q
    convention: {gripper: gripper_to_base, camera: target_to_camera}   # these are the defaults
    poses:
      - gripper: {xyz: [500, 0, 600], rpy: [0, 0, 30]}
        camera: {xyz: [10, -20, 400], quaternion: [0, 0, 0, 1]}
      - q: [100, 10, -20, 30]    # joint values in the robot file's units
        camera: {matrix: [[1, 0, 0, 10], [0, 1, 0, 0], [0, 0, 1, 400], [0, 0, 0, 1]]}

``gripper_to_base`` is the gripper's pose in the base frame, ``T_base_gripper`` (it maps gripper
coordinates to base coordinates: OpenCV's ``R_gripper2base``); ``base_to_gripper`` is its
inverse. ``target_to_camera`` is the target's pose in the camera frame, ``T_camera_target``.
A pose is ``xyz`` with one of ``rpy`` (roll, pitch, yaw: ``Rz Ry Rx``), ``quaternion``
(x, y, z, w), or a 4x4 ``matrix`` alone.

A result file holds X, the target's pose W, their residuals and X's covariance::

    units: {length: mm, angle: deg}
    handeye:
      mode: eye_in_hand
      method: joint
      X: {xyz: [...], rpy: [...]}        # T_gripper_camera (eye_to_hand: T_base_camera)
      target: {xyz: [...], rpy: [...]}   # T_base_target (eye_to_hand: T_gripper_target)
      covariance_si: [[...] x 6]         # X's rotation (rad) then translation (m)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import yaml
from pydantic import Field, model_validator

from armkit.calibration.handeye import HandEyeResult
from armkit.errors import InputError, ModelFileError
from armkit.io.documents import StrictModel, UnitsField, Value, read_yaml, validated
from armkit.kinematics.forward import fk
from armkit.io.robot_files import robot_named_in
from armkit.model.robot import Units
from armkit.spatial import invert, matrix_to_rpy, quat_to_matrix, rpy_to_matrix

Vector3 = Annotated[list[Value], Field(min_length=3, max_length=3)]
Row4 = Annotated[list[Value], Field(min_length=4, max_length=4)]
MAX_POSES = 100_000             # pose pairs in one file


class PoseField(StrictModel):
    """A pose in a file: xyz with rpy or a quaternion, or a whole 4x4 matrix."""

    xyz: Vector3 | None = None
    rpy: Vector3 | None = None
    quaternion: Row4 | None = None
    matrix: Annotated[list[Row4], Field(min_length=4, max_length=4)] | None = None

    @model_validator(mode="after")
    def _one_form(self):
        if self.matrix is not None:
            if self.xyz or self.rpy or self.quaternion:
                raise ValueError("expected a matrix alone, found it with xyz, rpy or quaternion")
            return self
        if self.xyz is None:
            raise ValueError("expected xyz with rpy or quaternion, or a matrix, found no xyz")
        if (self.rpy is None) == (self.quaternion is None):
            raise ValueError("expected one of rpy or quaternion with xyz, found "
                             + ("both" if self.rpy is not None else "neither"))
        if self.quaternion is not None and abs(math.hypot(*self.quaternion) - 1) > 1e-6:
            raise ValueError(f"expected a unit quaternion (x, y, z, w), found norm "
                             f"{math.hypot(*self.quaternion):.6g}")
        return self

    def to_si(self, units: Units) -> np.ndarray:
        T = np.eye(4)
        if self.matrix is not None:
            T[:] = self.matrix
            T[:3, 3] = units.length_to_si(T[:3, 3])
            return T
        T[:3, 3] = units.length_to_si(self.xyz)
        T[:3, :3] = (rpy_to_matrix(units.angle_to_si(self.rpy)) if self.rpy is not None
                     else quat_to_matrix(self.quaternion))
        return T


def rigid_pose(pose: PoseField, units: Units, path: str, field: str) -> np.ndarray:
    """The pose (4, 4) in SI, or a ModelFileError if a matrix is not a rigid transform."""
    T = pose.to_si(units)
    R = T[:3, :3]
    off = np.abs(R @ R.T - np.eye(3)).max()
    if off > 1e-6 or np.linalg.det(R) < 0 or np.abs(T[3] - [0, 0, 0, 1]).max() > 1e-9:
        raise ModelFileError(path, field, "a rigid transform (orthonormal rotation, det +1, "
                             "last row 0 0 0 1)", f"a rotation off by {off:.3g}"
                             if off > 1e-6 else "a reflection or another last row")
    return T


class ConventionField(StrictModel):
    gripper: Literal["gripper_to_base", "base_to_gripper"] = "gripper_to_base"
    camera: Literal["target_to_camera", "camera_to_target"] = "target_to_camera"


class PosePairField(StrictModel):
    gripper: PoseField | None = None
    q: list[Value] | None = None
    camera: PoseField

    @model_validator(mode="after")
    def _one_robot_pose(self):
        if (self.gripper is None) == (self.q is None):
            raise ValueError("expected one of gripper (a pose) or q (joint values), found "
                             + ("both" if self.q is not None else "neither"))
        return self


class PosesFile(StrictModel):
    units: UnitsField
    mode: Literal["eye_in_hand", "eye_to_hand"]
    robot: str | None = None
    convention: ConventionField = ConventionField()
    poses: list[PosePairField] = Field(min_length=1, max_length=MAX_POSES)


@dataclass(frozen=True)
class HandEyePoses:
    """Pose pairs read from a file, SI: ``T_base_gripper`` and ``T_camera_target``, (N, 4, 4)."""

    robot_poses: np.ndarray
    camera_poses: np.ndarray
    mode: str
    units: Units


def read_handeye_poses(path: str | Path) -> HandEyePoses:
    """Read a hand-eye poses file (see the module's docstring).

    Raises
    ------
    ModelFileError
        Naming the file, the field (``poses[3].camera.rpy``), what was expected and found.
    """
    path = str(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping with units, mode and poses",
                             type(document).__name__)
    spec = validated(path, document, PosesFile)
    units = Units(spec.units.length, spec.units.angle)
    needs_robot = [i for i, p in enumerate(spec.poses) if p.q is not None]
    model = None
    if needs_robot:
        if spec.robot is None:
            raise ModelFileError(path, "robot", "a robot name or file (poses give joint values "
                                 "q)", "nothing")
        model = robot_named_in(path, spec.robot)
    G, C = [], []
    for i, pair in enumerate(spec.poses):
        if pair.q is not None:
            if len(pair.q) != model.n:
                raise ModelFileError(path, f"poses[{i}].q", f"{model.n} joint values "
                                     f"({model.name})", f"{len(pair.q)}")
            G.append(fk(model, model.q_to_si(pair.q)))
        else:
            G.append(rigid_pose(pair.gripper, units, path, f"poses[{i}].gripper"))
        C.append(rigid_pose(pair.camera, units, path, f"poses[{i}].camera"))
    G, C = np.array(G), np.array(C)
    if spec.convention.gripper == "base_to_gripper":
        G = invert(G)
    if spec.convention.camera == "camera_to_target":
        C = invert(C)
    return HandEyePoses(G, C, spec.mode, units)


# --- results -----------------------------------------------------------------------------------

def _num(x: float) -> float:
    return float(f"{float(x):.15g}")


def pose_document(T: np.ndarray, units: Units) -> dict:
    """A pose (4, 4) in SI as ``{xyz, rpy}`` in `units`."""
    return {"xyz": [_num(v) for v in units.length_from_si(T[:3, 3])],
            "rpy": [_num(v) for v in units.angle_from_si(matrix_to_rpy(T[:3, :3]))]}


def handeye_document(result: HandEyeResult, units: Units) -> dict:
    """A solved hand-eye result as a result-file document in `units`.

    Raises
    ------
    InputError
        If the result is a refusal (it has no X to write).
    """
    if not result.success:
        raise InputError(f"hand-eye result: expected a solved one to write, found a refusal "
                         f"({result.reason})")
    deg = units.angle_from_si
    return {"units": {"length": units.length, "angle": units.angle},
            "handeye": {
                "mode": result.mode, "method": result.method,
                "X": pose_document(result.X, units),
                "target": pose_document(result.W, units),
                "std": {"rotation": [_num(v) for v in deg(result.rotation_std)],
                        "translation": [_num(v) for v in
                                        units.length_from_si(result.translation_std)]},
                "residuals_rms": {"rotation": _num(deg(result.rotation_rms)),
                                  "translation": _num(units.length_from_si(
                                      result.translation_rms))},
                "covariance_si": [[_num(v) for v in row] for row in result.covariance]}}


def write_handeye_result(result: HandEyeResult, path: str | Path, units: Units) -> None:
    """Write a solved hand-eye result as a YAML result file (read back by
    `armkit.io.camera.read_camera_mount`)."""
    text = yaml.safe_dump(handeye_document(result, units), sort_keys=False,
                          default_flow_style=None)
    Path(path).write_text(text, encoding="utf-8")

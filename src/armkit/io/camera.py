"""Camera mount files: a fixed camera-to-base transform, or a hand-eye result file.

A camera-to-base file (YAML) gives the camera's (or sensor's) pose in the robot's base frame,
``T_base_camera``, in the file's units::

    units: {length: mm, angle: deg}
    camera_to_base: {xyz: [1200, 0, 800], rpy: [180, 0, 90]}

A hand-eye result file (written by ``armkit handeye --out``, see `armkit.io.handeye`) serves in
its place; `read_camera_mount` reads either into a `CameraMount`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator

from armkit.calibration.frames import CameraMount
from armkit.errors import ModelFileError
from armkit.io.documents import Value, StrictModel, UnitsField, read_yaml, validated
from armkit.io.handeye import PoseField, rigid_pose
from armkit.model.robot import Units

Row6 = Annotated[list[Value], Field(min_length=6, max_length=6)]


class CameraToBaseFile(StrictModel):
    units: UnitsField
    camera_to_base: PoseField


class StdField(StrictModel):
    rotation: Annotated[list[Value], Field(min_length=3, max_length=3)]
    translation: Annotated[list[Value], Field(min_length=3, max_length=3)]


class ResidualsField(StrictModel):
    rotation: Value
    translation: Value


class HandEyeField(StrictModel):
    mode: Literal["eye_in_hand", "eye_to_hand"]
    method: str = ""
    X: PoseField
    target: PoseField | None = None
    std: StdField | None = None
    residuals_rms: ResidualsField | None = None
    covariance_si: Annotated[list[Row6], Field(min_length=6, max_length=6)] | None = None

    @field_validator("covariance_si")
    @classmethod
    def _symmetric(cls, v):
        if v is not None:
            C = np.array(v)
            if not np.allclose(C, C.T, rtol=1e-6, atol=1e-18) or np.linalg.eigvalsh(
                    (C + C.T) / 2).min() < -1e-12 * max(np.abs(C).max(), 1e-300):
                raise ValueError("expected a symmetric positive semi-definite 6x6 matrix, "
                                 "found one that is not")
        return v


class HandEyeFile(StrictModel):
    units: UnitsField
    handeye: HandEyeField


def parse_camera_mount(document, path: str = "<camera>") -> CameraMount:
    """A `CameraMount` from a parsed camera-to-base or hand-eye result document.

    Raises
    ------
    ModelFileError
    """
    if not isinstance(document, dict):
        raise ModelFileError(path, "", "a mapping with units and camera_to_base or handeye",
                             type(document).__name__)
    if "handeye" in document:
        model = HandEyeFile
    elif "camera_to_base" in document:
        model = CameraToBaseFile
    else:
        raise ModelFileError(path, "", "a camera_to_base pose or a handeye result",
                             f"fields {', '.join(map(str, document)) or 'none'}")
    spec = validated(path, document, model)
    units = Units(spec.units.length, spec.units.angle)
    if isinstance(spec, CameraToBaseFile):
        return CameraMount("fixed", rigid_pose(spec.camera_to_base, units, path, "camera_to_base"))
    h = spec.handeye
    cov = None if h.covariance_si is None else np.array(h.covariance_si, dtype=float)
    return CameraMount(h.mode, rigid_pose(h.X, units, path, "handeye.X"), cov)


def read_camera_mount(path: str | Path) -> CameraMount:
    """Read a camera-to-base file or a hand-eye result file into a `CameraMount`.

    Raises
    ------
    ModelFileError
        Naming the file, the field, what was expected and what was found.
    """
    return parse_camera_mount(read_yaml(path), str(path))

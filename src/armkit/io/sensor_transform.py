"""Sensor-to-base transform files: the sensor's pose in the robot's base frame (T_base_sensor).

A small YAML file, in the file's units, either as a position and roll-pitch-yaw
(``R = Rz(yaw) Ry(pitch) Rx(roll)``, as URDF)::

    # the LiDAR's pose in the robot's base frame
    units: {length: mm, angle: deg}
    xyz: [1200, -350, 800]
    rpy: [0, 0, 90]

or as a 4x4 homogeneous matrix (translation in the length unit; no angle unit needed)::

    units: {length: m}
    matrix:
      - [0, -1, 0, 1.2]
      - [1,  0, 0, -0.35]
      - [0,  0, 1, 0.8]
      - [0,  0, 0, 1]
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, ValidationError, model_validator

from armkit.errors import ModelFileError
from armkit.io.documents import StrictModel, read_yaml, validation_error
from armkit.spatial import pose_from_xyz_rpy

Vector3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Row4 = Annotated[list[float], Field(min_length=4, max_length=4)]


class _Units(StrictModel):
    length: Literal["m", "mm"]
    angle: Literal["rad", "deg"] | None = None


class _SensorToBase(StrictModel):
    units: _Units
    xyz: Vector3 | None = None
    rpy: Vector3 | None = None
    matrix: Annotated[list[Row4], Field(min_length=4, max_length=4)] | None = None

    @model_validator(mode="after")
    def _one_form(self):
        pose = self.xyz is not None or self.rpy is not None
        if pose and self.matrix is not None:
            raise ValueError("expected either xyz and rpy or a matrix, found both")
        if not pose and self.matrix is None:
            raise ValueError("expected xyz and rpy, or a matrix, found neither")
        if pose and (self.xyz is None or self.rpy is None):
            raise ValueError(f"expected both xyz and rpy, found only "
                             f"{'xyz' if self.xyz is not None else 'rpy'}")
        if pose and self.units.angle is None:
            raise ValueError("expected units.angle (rad or deg) for rpy, found none")
        return self


def read_sensor_to_base(path: str | Path) -> NDArray:
    """The sensor's pose in the robot's base frame, T_base_sensor, from a YAML file, in m.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    T_base_sensor : ndarray, shape (4, 4)
        Maps points from the sensor frame to the base frame: ``p_base = T @ [p_sensor, 1]``.

    Raises
    ------
    ModelFileError
        Unreadable, not YAML, a missing or unknown field, or a matrix that is not a rigid
        transform (rotation part orthonormal with det +1 within 1e-6, last row 0 0 0 1).
    """
    name = str(path)
    document = read_yaml(name)
    if not isinstance(document, dict):
        raise ModelFileError(name, "", "a mapping with units and xyz/rpy or matrix",
                             type(document).__name__)
    try:
        spec = _SensorToBase.model_validate(document)
    except ValidationError as err:
        raise validation_error(name, err, _SensorToBase) from None
    scale = 1e-3 if spec.units.length == "mm" else 1.0
    if spec.matrix is None:
        return pose_from_xyz_rpy(np.array(spec.xyz) * scale, spec.rpy,
                                 degrees=spec.units.angle == "deg")
    T = np.array(spec.matrix, float)
    R = T[:3, :3]
    off = float(np.abs(R @ R.T - np.eye(3)).max())
    if off > 1e-6 or np.linalg.det(R) < 0:
        raise ModelFileError(name, "matrix", "a rotation part that is orthonormal with det +1",
                             f"one off by {off:.3g}" if off > 1e-6 else "a reflection (det -1)")
    if not np.allclose(T[3], [0, 0, 0, 1], atol=1e-12):
        raise ModelFileError(name, "matrix[3]", "[0, 0, 0, 1]", str(T[3].tolist()))
    T[:3, 3] *= scale
    return T

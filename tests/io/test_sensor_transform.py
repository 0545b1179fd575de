"""Sensor-to-base transform files: xyz/rpy and matrix forms, units, and bad files."""

from __future__ import annotations

import numpy as np
import pytest

from armkit.errors import ModelFileError
from armkit.io.sensor_transform import read_sensor_to_base
from armkit.spatial import pose_from_xyz_rpy


def write(tmp_path, text, name="tf.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_xyz_rpy_in_millimetres_and_degrees(tmp_path):
    T = read_sensor_to_base(write(tmp_path, "units: {length: mm, angle: deg}\n"
                                            "xyz: [1200, -350, 800]\nrpy: [10, -20, 90]\n"))
    expected = pose_from_xyz_rpy([1.2, -0.35, 0.8], np.deg2rad([10, -20, 90]))
    np.testing.assert_allclose(T, expected, atol=1e-15)


def test_matrix_in_metres(tmp_path):
    T = read_sensor_to_base(write(tmp_path, "units: {length: mm}\nmatrix:\n"
                                            "  - [0, -1, 0, 1200]\n  - [1, 0, 0, -350]\n"
                                            "  - [0, 0, 1, 800]\n  - [0, 0, 0, 1]\n"))
    np.testing.assert_allclose(T, [[0, -1, 0, 1.2], [1, 0, 0, -0.35], [0, 0, 1, 0.8],
                                   [0, 0, 0, 1]])


@pytest.mark.parametrize("text, message", [
    ("xyz: [0, 0, 0]\nrpy: [0, 0, 0]\n", r"tf\.yaml: units: expected a value, found nothing"),
    ("units: {length: cm, angle: deg}\nxyz: [0, 0, 0]\nrpy: [0, 0, 0]\n",
     r"tf\.yaml: units\.length: expected 'm' or 'mm', found 'cm'"),
    ("units: {length: m}\nxyz: [0, 0, 0]\nrpy: [0, 0, 0]\n",
     r"tf\.yaml: expected units\.angle \(rad or deg\) for rpy, found none"),
    ("units: {length: m, angle: rad}\nxyz: [0, 0]\nrpy: [0, 0, 0]\n",
     r"tf\.yaml: xyz: expected at least 3 item\(s\), found 2"),
    ("units: {length: m, angle: rad}\nxyz: [0, 0, 0]\n",
     r"tf\.yaml: expected both xyz and rpy, found only xyz"),
    ("units: {length: m}\n", r"tf\.yaml: expected xyz and rpy, or a matrix, found neither"),
    ("units: {length: m, angle: rad}\nxyz: [0, 0, 0]\nrpy: [0, 0, 0]\nxzy: [1, 2, 3]\n",
     r"tf\.yaml: top level: expected one of units, xyz, rpy, matrix \(did you mean 'xyz'\?\), "
     r"found unknown field 'xzy'"),
    ("units: {length: m}\nmatrix: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]]\n",
     r"tf\.yaml: matrix: expected a rotation part that is orthonormal with det \+1, found one "
     r"off by 3"),
    ("units: {length: m}\nmatrix: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, 1]]\n",
     r"tf\.yaml: matrix: expected .* found a reflection"),
    ("units: {length: m}\nmatrix: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]\n",
     r"tf\.yaml: matrix\[3\]: expected \[0, 0, 0, 1\], found \[0\.0, 0\.0, 1\.0, 1\.0\]"),
    ("- 1\n- 2\n", r"tf\.yaml: expected a mapping with units and xyz/rpy or matrix, found list"),
    ("units: {length: m, angle: rad}\nxyz: [0, 0, .nan]\nrpy: [0, 0, 0]\n",
     r"tf\.yaml: xyz\[2\]: expected a finite number, found nan"),
])
def test_bad_files(tmp_path, text, message):
    with pytest.raises(ModelFileError, match=message):
        read_sensor_to_base(write(tmp_path, text))

"""Camera-to-base files and hand-eye result files as camera mounts."""

from __future__ import annotations

import re

import numpy as np
import pytest

from armkit.calibration.frames import points_to_base
from armkit.errors import ModelFileError
from armkit.io.camera import read_camera_mount
from armkit.spatial import pose_from_xyz_rpy


def _file(tmp_path, text):
    path = tmp_path / "camera.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_camera_to_base_file(tmp_path):
    path = _file(tmp_path, "units: {length: mm, angle: deg}\n"
                           "camera_to_base: {xyz: [1200, 0, 800], rpy: [180, 0, 90]}\n")
    mount = read_camera_mount(path)
    T = pose_from_xyz_rpy([1.2, 0, 0.8], np.deg2rad([180, 0, 90]))
    assert mount.kind == "fixed" and mount.covariance is None
    assert np.allclose(mount.T, T, atol=1e-15)
    assert np.allclose(points_to_base(mount, [0, 0, 1.0]), [1.2, 0, -0.2], atol=1e-12)


@pytest.mark.parametrize("text, pattern", [
    ("units: {length: mm, angle: deg}\n", r"expected a camera_to_base pose or a handeye result, "
                                          r"found fields units"),
    ("[1, 2]\n", r"expected a mapping with units and camera_to_base or handeye, found list"),
    ("camera_to_base: {xyz: [0, 0, 0], rpy: [0, 0, 0]}\n", r"units: expected a value, found "
                                                           r"nothing"),
    ("units: {length: mm, angle: deg}\ncamera_to_base: {xyz: [0, 0], rpy: [0, 0, 0]}\n",
     r"camera_to_base\.xyz: expected at least 3 item"),
    ("units: {length: mm, angle: deg}\ncamera_to_base: {matrix: [[1, 0, 0, 0], [0, 1, 0, 0], "
     "[0, 0, -1, 0], [0, 0, 0, 1]]}\n", r"camera_to_base: expected a rigid transform .*found a "
                                        r"reflection"),
    ("units: {length: mm, angle: deg}\nhandeye: {mode: eye_in_hand}\n",
     r"handeye\.X: expected a value, found nothing"),
    ("units: {length: mm, angle: deg}\nhandeye: {mode: eye_in_hand, X: {xyz: [0, 0, 0], "
     "rpy: [0, 0, 0]}, covariance_si: [[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], "
     "[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, -1]]}\n",
     r"handeye\.covariance_si: expected a symmetric positive semi-definite 6x6 matrix"),
])
def test_bad_camera_files(tmp_path, text, pattern):
    path = _file(tmp_path, text)
    with pytest.raises(ModelFileError) as err:
        read_camera_mount(path)
    message = str(err.value)
    assert message.startswith(str(path)) and re.search(pattern, message), message

"""Hand-eye poses files and result files: read in SI, and every mistake named precisely."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

import armkit
from armkit.calibration.frames import points_to_base
from armkit.calibration.handeye import handeye
from armkit.errors import InputError, ModelFileError
from armkit.io.camera import read_camera_mount
from armkit.io.handeye import read_handeye_poses, write_handeye_result
from armkit.model import Units
from armkit.spatial import invert, matrix_to_quat, matrix_to_rpy
from tests.calibration.synthetic import handeye_data

EXAMPLE = Path(__file__).parents[2] / "examples" / "calibration" / "handeye_poses.yaml"


def _pose(T, form="rpy"):
    if form == "matrix":
        M = np.array(T)
        M[:3, 3] *= 1000
        return {"matrix": M.tolist()}
    doc = {"xyz": (T[:3, 3] * 1000).tolist()}
    if form == "rpy":
        doc["rpy"] = np.rad2deg(matrix_to_rpy(T[:3, :3])).tolist()
    else:
        doc["quaternion"] = matrix_to_quat(T[:3, :3]).tolist()
    return doc


def _write(path, document):
    path.write_text(yaml.safe_dump(document), encoding="utf-8")
    return path


def _document(G, C, **extra):
    forms = ("rpy", "quaternion", "matrix")
    return {"units": {"length": "mm", "angle": "deg"}, "mode": "eye_in_hand", **extra,
            "poses": [{"gripper": _pose(g, forms[k % 3]), "camera": _pose(c, forms[(k + 1) % 3])}
                      for k, (g, c) in enumerate(zip(G, C))]}


def test_every_pose_form_reads_back_in_si(tmp_path):
    G, C, X, _ = handeye_data(7, seed=1)
    data = read_handeye_poses(_write(tmp_path / "p.yaml", _document(G, C)))
    assert data.mode == "eye_in_hand" and data.units == Units("mm", "deg")
    assert np.abs(data.robot_poses - G).max() < 1e-12
    assert np.abs(data.camera_poses - C).max() < 1e-12
    assert np.abs(handeye(data.robot_poses, data.camera_poses).X - X).max() < 1e-9


def test_conventions_invert_the_poses(tmp_path):
    G, C, _, _ = handeye_data(5, seed=2)
    doc = _document(invert(G), invert(C), convention={"gripper": "base_to_gripper",
                                                      "camera": "camera_to_target"})
    data = read_handeye_poses(_write(tmp_path / "p.yaml", doc))
    assert np.abs(data.robot_poses - G).max() < 1e-12
    assert np.abs(data.camera_poses - C).max() < 1e-12


def test_joint_values_through_a_named_robot(tmp_path):
    robot = armkit.robot("inspection_6dof")
    q = np.deg2rad([[10, -20, 30, 5, 40, -10], [0, 10, -30, 20, 10, 60]])
    G = armkit.fk(robot, q)
    doc = {"units": {"length": "mm", "angle": "deg"}, "mode": "eye_to_hand",
           "robot": "inspection_6dof",
           "poses": [{"q": np.rad2deg(qk).tolist(), "camera": _pose(np.eye(4))} for qk in q]}
    data = read_handeye_poses(_write(tmp_path / "p.yaml", doc))
    assert np.abs(data.robot_poses - G).max() < 1e-12 and data.mode == "eye_to_hand"


def test_the_example_file():
    data = read_handeye_poses(EXAMPLE)
    result = handeye(data.robot_poses, data.camera_poses, data.mode)
    assert result.success
    # generate.py's true X: xyz 40 -25 90 mm, rpy 5 -3 92 deg; 0.1 deg and 0.5 mm of noise.
    assert np.abs(result.X[:3, 3] * 1000 - [40, -25, 90]).max() < 1.5
    assert np.abs(np.rad2deg(matrix_to_rpy(result.X[:3, :3])) - [5, -3, 92]).max() < 0.1


def _fails(tmp_path, document, pattern):
    path = _write(tmp_path / "bad.yaml", document)
    with pytest.raises(ModelFileError) as err:
        read_handeye_poses(path)
    message = str(err.value)
    assert "\n" not in message and message.startswith(str(path))
    assert re.search(pattern, message), message


def test_bad_poses_files(tmp_path):
    G, C, _, _ = handeye_data(3, seed=4)
    good = _document(G, C)
    bad = dict(good, units={"length": "inch", "angle": "deg"})
    _fails(tmp_path, bad, r"units\.length: expected 'mm' or 'm', found 'inch'")
    bad = dict(good, mode="eye_on_hand")
    _fails(tmp_path, bad, r"mode: expected 'eye_in_hand' or 'eye_to_hand', found 'eye_on_hand'")
    bad = _document(G, C)
    bad["poses"][0]["gripper"] = {"xyz": [0, 0, 0], "rpy": [0, 0, 0], "quaternion": [0, 0, 0, 1]}
    _fails(tmp_path, bad, r"poses\[0\]\.gripper: expected one of rpy or quaternion with xyz, "
                          r"found both")
    bad["poses"][0]["gripper"] = {"xyz": [0, 0, 0], "quaternion": [0, 0, 0, 2]}
    _fails(tmp_path, bad, r"poses\[0\]\.gripper: expected a unit quaternion .*found norm 2")
    bad["poses"][0]["gripper"] = {"matrix": [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0],
                                             [0, 0, 0, 1]]}
    _fails(tmp_path, bad, r"poses\[0\]\.gripper: expected a rigid transform .*found a rotation "
                          r"off by 3")
    bad["poses"][0]["gripper"] = {"xyz": [0, 0, float("nan")], "rpy": [0, 0, 0]}
    _fails(tmp_path, bad, r"poses\[0\]\.gripper\.xyz\[2\]: expected a finite number")
    bad = _document(G, C)
    del bad["poses"][1]["camera"]
    _fails(tmp_path, bad, r"poses\[1\]\.camera: expected a value, found nothing")
    bad = _document(G, C)
    bad["poses"][2] = {"q": [1, 2, 3, 4, 5, 6], "camera": bad["poses"][2]["camera"]}
    _fails(tmp_path, bad, r"robot: expected a robot name or file \(poses give joint values q\), "
                          r"found nothing")
    bad["robot"] = "water_supply"
    _fails(tmp_path, bad, r"poses\[2\]\.q: expected 4 joint values \(water_supply\), found 6")
    bad["robot"] = "no_such_robot"
    _fails(tmp_path, bad, r"robot: expected a built-in robot name or a robot file, found "
                          r"'no_such_robot'")
    bad = dict(good, pose=[])
    _fails(tmp_path, bad, r"top level: expected one of .*poses.*unknown field 'pose'")
    path = tmp_path / "twice.yaml"
    path.write_text("units: {length: mm, angle: deg}\nmode: eye_in_hand\nmode: eye_in_hand\n",
                    encoding="utf-8")
    with pytest.raises(ModelFileError, match="key 'mode' given twice"):
        read_handeye_poses(path)
    with pytest.raises(ModelFileError, match="expected a readable file"):
        read_handeye_poses(tmp_path / "missing.yaml")


def test_result_file_round_trip_and_camera_mount(tmp_path):
    G, C, X, W = handeye_data(8, seed=6, noise_rotation=0.002, noise_translation=0.0005)
    result = handeye(G, C)
    path = tmp_path / "result.yaml"
    write_handeye_result(result, path, Units("mm", "deg"))
    mount = read_camera_mount(path)
    assert mount.kind == "eye_in_hand"
    assert np.abs(mount.T - result.X).max() < 1e-12
    assert np.allclose(mount.covariance, result.covariance, rtol=1e-12, atol=1e-30)
    p = np.array([0.1, 0.0, 0.6])
    assert np.allclose(points_to_base(mount, p, G[0]), points_to_base(result, p, G[0]))
    refused = handeye(*handeye_data(6, seed=1, axis=[0, 0, 1])[:2])
    with pytest.raises(InputError, match="expected a solved one to write, found a refusal"):
        write_handeye_result(refused, tmp_path / "no.yaml", Units())

"""A URDF's visual elements (armkit.io.visuals) placed as pinocchio places them, on the real
URDFs of example-robot-data (STL and Collada meshes), and drawn by `armkit view`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import armkit
from armkit.io.visuals import mesh_file, read_visuals

SHARE = next(Path(p) for p in map(Path, sys.path) if (p / "cmeel.prefix").is_dir()) / \
    "cmeel.prefix" / "share"
ROBOTS = SHARE / "example-robot-data" / "robots"
CASES = [("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),      # STL meshes
         ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),            # Collada
         ("ur_description/urdf/ur5_robot.urdf", "tool0")]


@pytest.mark.slow
@pytest.mark.parametrize("file, tip", CASES)
def test_visuals_sit_where_pinocchio_puts_them(file, tip):
    path = ROBOTS / file
    robot = armkit.load_robot(path, tip=tip)
    visuals = read_visuals(robot)
    model, _, geometry = pin.buildModelsFromUrdf(str(path), package_dirs=[str(SHARE)])
    data, placed = model.createData(), pin.GeometryData(geometry)
    rng = np.random.default_rng(0)
    for q in rng.uniform(*robot.chain.sampling_limits, (3, robot.n)):
        q_pin = pin.neutral(model)
        for name, value in zip(robot.joint_names, q):
            j = model.getJointId(name)
            q_pin[model.joints[j].idx_q] = value
        pin.forwardKinematics(model, data, q_pin)
        pin.updateGeometryPlacements(model, data, geometry, placed)
        frames = armkit.fk_frames(robot, q)
        theirs = {g.name: placed.oMg[i].homogeneous
                  for i, g in enumerate(geometry.geometryObjects)}
        assert len(visuals.shapes) >= 5
        for shape in visuals.shapes:
            np.testing.assert_allclose(frames[shape.link] @ shape.T, theirs[shape.name],
                                       atol=1e-9, err_msg=shape.name)


def test_meshes_are_found_as_ros_finds_them(tmp_path):
    package = tmp_path / "my_arm"
    (package / "urdf").mkdir(parents=True)
    (package / "meshes").mkdir()
    (package / "meshes" / "a.stl").write_text("solid a\nendsolid a\n")
    urdf = package / "urdf" / "arm.urdf"
    assert mesh_file("package://my_arm/meshes/a.stl", urdf) == package / "meshes" / "a.stl"
    assert mesh_file("../meshes/a.stl", urdf) == package / "urdf" / ".." / "meshes" / "a.stl"
    assert mesh_file("package://other/meshes/a.stl", urdf) is None


def test_a_robot_without_a_urdf_has_no_visuals():
    assert read_visuals(armkit.robot("ur5")) is None


@pytest.mark.slow
def test_view_draws_a_urdfs_visual_meshes(tmp_path):
    out = tmp_path / "so101.html"
    done = subprocess.run([sys.executable, "-m", "armkit", "view",
                           str(ROBOTS / CASES[0][0]), "--tip", CASES[0][1], "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    page = out.read_text()
    assert "arm (URDF visual meshes)" in page and page.count('type="range"') == 5

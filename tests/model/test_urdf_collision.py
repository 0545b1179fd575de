"""The URDF reader's <collision> elements: what it reads, where it places them, what it refuses."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.io.urdf import read_urdf
from armkit.spatial import pose_from_xyz_rpy
from tests.model.urdf_collision_files import ARM, TIP


@pytest.fixture
def arm(tmp_path):
    path = tmp_path / "hand.urdf"
    path.write_text(ARM)
    return path


def test_collisions_are_placed_on_their_chain_links(arm):
    table = read_urdf(arm, tip=TIP)
    found = {(c.link, c.index): c for c in table.collisions}
    assert sorted(found) == [("base", 0), ("l1", 0), ("l2", 0), ("sensor", 0), ("tool", 0)]
    assert table.detached == ("finger",)          # moved by a joint off the chain: not read
    chain_link = {name: c.chain_link for (name, _), c in found.items()}
    assert chain_link == {"base": 0, "l1": 1, "sensor": 1, "l2": 2, "tool": 2}
    kinds = {name: (c.kind, c.size.tolist()) for (name, _), c in found.items()}
    assert kinds == {"base": ("sphere", [0.1]), "l1": ("cylinder", [0.05, 0.4]),
                     "sensor": ("box", [0.1, 0.3, 0.02]), "l2": ("sphere", [0.03]),
                     "tool": ("cylinder", [0.02, 0.06])}
    # The sensor's box: its origin after the fixed joint's (0.4 m along x, turned 90 deg).
    expected = pose_from_xyz_rpy([0.4, 0, 0], [0, 0, np.pi / 2]) @ \
        pose_from_xyz_rpy([0, 0.1, 0], [0, 0, 0])
    np.testing.assert_allclose(found["sensor", 0].T, expected, atol=1e-15)
    np.testing.assert_allclose(found["tool", 0].T, pose_from_xyz_rpy([0.15, 0, 0], [0, 0, 0]))
    np.testing.assert_allclose(found["l1", 0].T,
                               pose_from_xyz_rpy([0.2, 0, 0], [0, np.pi / 2, 0]))
    assert not found["l1", 0].T.flags.writeable


def test_a_mesh_whose_file_is_missing_is_kept_unread(arm, tmp_path):
    path = tmp_path / "mesh.urdf"
    path.write_text(ARM.replace('<sphere radius="0.03"/>',
                                '<mesh filename="package://missing/l2.stl" scale="1 2 1"/>'))
    (c,) = [c for c in read_urdf(path, tip=TIP).collisions if c.link == "l2"]
    assert c.kind == "mesh" and c.size.tolist() == [1, 2, 1] and c.vertices is None
    assert "was not found" in c.note


WHERE_L1 = "link 'l1' <collision>[0]"


@pytest.mark.parametrize("old, new, field, expected, found", [
    ('radius="0.05" length="0.4"', 'radius="-0.05" length="0.4"', f"{WHERE_L1} <cylinder> radius",
     "a positive length (m)", "'-0.05'"),
    ('radius="0.05" length="0.4"', 'radius="0.05" length="0"', f"{WHERE_L1} <cylinder> length",
     "a positive length (m)", "'0'"),
    ('radius="0.05" length="0.4"', 'radius="0.05"', f"{WHERE_L1} <cylinder> length",
     "a positive length (m)", "none"),
    ('radius="0.05" length="0.4"', 'radius="nan" length="0.4"', f"{WHERE_L1} <cylinder> radius",
     "a finite number", "'nan'"),
    ('radius="0.05" length="0.4"', 'radius="5e3" length="0.4"', f"{WHERE_L1} <cylinder> radius",
     "a finite number of at most 1000 in size", "'5e3'"),
    ('<cylinder radius="0.05" length="0.4"/>', '<cone radius="0.05" length="0.4"/>',
     f"{WHERE_L1} <geometry>", "one of <box>, <cylinder>, <sphere> or <mesh>", "<cone>"),
    ('<cylinder radius="0.05" length="0.4"/>', "", f"{WHERE_L1} <geometry>",
     "one of <box>, <cylinder>, <sphere> or <mesh>", "nothing"),
    ('<cylinder radius="0.05" length="0.4"/>', '<sphere radius="1"/><sphere radius="1"/>',
     f"{WHERE_L1} <geometry>", "one of <box>, <cylinder>, <sphere> or <mesh>",
     "<sphere> <sphere>"),
    ('xyz="0.2 0 0" rpy="0 1.5707963267948966 0"', 'xyz="0.2 0" rpy="0 1.5707963267948966 0"',
     f"{WHERE_L1} <origin> xyz", "3 finite numbers", "'0.2 0'"),
    ('xyz="0.2 0 0" rpy="0 1.5707963267948966 0"', 'xyz="0.2 0 0" rpy="0 pi/2 0"',
     f"{WHERE_L1} <origin> rpy", "3 finite numbers", "'0 pi/2 0'"),
    ('<box size="0.1 0.3 0.02"/>', '<box size="0.1 0.3"/>',
     "link 'sensor' <collision>[0] <box> size", "3 finite numbers", "'0.1 0.3'"),
    ('<box size="0.1 0.3 0.02"/>', '<box size="0.1 0 0.02"/>',
     "link 'sensor' <collision>[0] <box> size", "3 positive lengths (m)", "'0.1 0 0.02'"),
    ('<sphere radius="0.1"/>', '<sphere r="0.1"/>', "link 'base' <collision>[0] <sphere> radius",
     "a positive length (m)", "none"),
    ('<sphere radius="0.03"/>', '<sphere radius="١"/>',
     "link 'l2' <collision>[0] <sphere> radius", "a finite number", "'١'"),
    ('<geometry><cylinder radius="0.02" length="0.06"/></geometry>',
     '<cylinder radius="0.02" length="0.06"/>',
     "link 'tool' <collision>[0] <geometry>", "a <geometry> element", "none"),
    # A fixed joint that places a collision on the arm is read in full.
    ('<origin xyz="0.4 0 0" rpy="0 0 1.5707963267948966"/>', '<origin xyz="0.4 0 x"/>',
     "joint 'mount' <origin> xyz", "3 finite numbers", "'0.4 0 x'"),
])
def test_collision_mistakes(tmp_path, old, new, field, expected, found):
    assert old in ARM
    path = tmp_path / "bad.urdf"
    path.write_text(ARM.replace(old, new, 1))
    with pytest.raises(ModelFileError) as err:
        armkit.load_robot(path, tip=TIP)
    e = err.value
    assert (e.file, e.field, e.expected, e.found) == (str(path), field, expected, found), str(e)
    assert str(e) == f"{path}: {field}: expected {expected}, found {found}"


def test_collisions_off_the_arm_are_not_read(tmp_path):
    """The finger (moved by a joint off the chain) may hold anything: it is not part of the arm."""
    path = tmp_path / "finger.urdf"
    path.write_text(ARM.replace('<box size="0.01 0.01 0.05"/>', '<cone size="huge"/>'))
    table = read_urdf(path, tip=TIP)
    assert table.detached == ("finger",) and len(table.collisions) == 5
    # With the finger as the tip, it is on the chain and its collision is read.
    with pytest.raises(ModelFileError, match="link 'finger' <collision>\\[0\\] <geometry>"):
        read_urdf(path, tip="finger")


def test_yaml_wrapper_keeps_the_collisions(arm, tmp_path):
    wrapper = tmp_path / "arm.yaml"
    wrapper.write_text(f"name: hand\nunits: {{length: mm, angle: deg}}\nconvention: urdf\n"
                       f"urdf: {arm.name}\ntip: {TIP}\ntool: {{xyz: [0, 0, 100]}}\n")
    robot = armkit.robot(str(wrapper))
    assert len(robot.table.collisions) == 5 and robot.table.detached == ("finger",)


def test_yaml_wrapper_keeps_a_mimic_joints_leader(tmp_path):
    """The wrapper keeps all the URDF gives (here the leader off the chain of a mimic joint)."""
    from tests.model.test_real_urdfs import robot_file

    wrapper = tmp_path / "panda.yaml"
    wrapper.write_text("name: p\nunits: {length: mm, angle: deg}\nconvention: urdf\n"
                       f"urdf: {robot_file('panda_description/urdf/panda.urdf')}\n"
                       "tip: panda_rightfinger\ntool: {xyz: [0, 0, 10]}\n")
    robot = armkit.robot(str(wrapper))
    direct = armkit.load_robot(robot_file("panda_description/urdf/panda.urdf"),
                               tip="panda_rightfinger")
    assert robot.joint_names == direct.joint_names and robot.n == 8
    q = np.full(8, 0.01)
    expected = armkit.fk(direct, q) @ pose_from_xyz_rpy([0, 0, 0.01], [0, 0, 0])
    np.testing.assert_allclose(armkit.fk(robot, q), expected, atol=1e-15)

"""URDF chains: joint types, limits, tips of a tree, and the errors."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import ModelFileError
from armkit.spatial import rotz, transform

TREE = """<robot name="tree">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="hand"/><link name="camera"/>
  <joint name="yaw" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" velocity="0.2" effort="10"/></joint>
  <joint name="hand_mount" type="fixed"><parent link="l2"/><child link="hand"/>
    <origin xyz="0.05 0 0"/></joint>
  <joint name="camera_mount" type="fixed"><parent link="l1"/><child link="camera"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>"""


@pytest.fixture
def tree(tmp_path):
    path = tmp_path / "tree.urdf"
    path.write_text(TREE)
    return path


def test_chain_to_a_named_tip(tree):
    robot = armkit.model.chain_from_urdf(armkit.model.read_urdf(tree, tip="hand"))
    assert [j.name for j in robot.joints] == ["yaw", "slide"]
    assert robot.lower[0] == -np.inf and robot.upper[1] == 0.5
    assert robot.velocity_limits[1] == 0.2
    r = armkit.Robot("tree", robot)
    T = armkit.fk(r, [np.pi / 2, 0.2])
    np.testing.assert_allclose(T, transform(rotz(np.pi / 2), [0, 0.35, 0.3]), atol=1e-15)


def test_several_tips_and_none_named_lists_them(tree):
    with pytest.raises(ModelFileError, match=r"tip: expected the name of the tip link "
                                             r"\(the tree has several: hand, camera\)"):
        armkit.load_robot(tree)


def test_unknown_tip(tree):
    with pytest.raises(ModelFileError, match="tip: expected a link of the file"):
        armkit.model.read_urdf(tree, tip="gripper")


@pytest.mark.parametrize("old, new, words", [
    ('type="prismatic"', 'type="spherical"',
     "type: expected revolute or continuous or prismatic or fixed, found 'spherical'"),
    ('type="prismatic"', 'type="floating"',
     "type: expected revolute, continuous, prismatic or fixed on the chain to 'hand'"),
    ('<limit lower="0" upper="0.5"', '<limit upper="0.5"', "<limit>: expected lower and upper"),
    ('<limit lower="0" upper="0.5"', '<limit lower="0.6" upper="0.5"', "lower < upper"),
    ('xyz="0.1 0 0"', 'xyz="0.1 0"', "<origin> xyz: expected 3 finite numbers"),
    ('xyz="0.1 0 0"', 'xyz="0.1 0 nan"', "<origin> xyz: expected 3 finite numbers"),
    ('velocity="0.2"', 'velocity="fast"', "<limit> velocity: expected a finite number, found 'fast'"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 zero"/>', "<axis> xyz: expected 3 finite numbers"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="yaw"/>', "expected independent"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="0 0 0"/>', "<axis> xyz: expected a non-zero direction"),
    ("</robot>", "", "expected a readable URDF (XML) file"),
    ("<robot", "<sdf", "expected a <robot> root element, found <sdf>"),
])
def test_urdf_mistakes(tmp_path, old, new, words):
    path = tmp_path / "bad.urdf"
    path.write_text(TREE.replace(old, new).replace("</robot>", "</sdf>") if old == "<robot"
                    else TREE.replace(old, new))
    with pytest.raises(ModelFileError) as err:
        armkit.model.read_urdf(path, tip="hand")
    assert str(err.value).startswith(str(path)) and words in str(err.value), str(err.value)


def test_yaml_wrapper_adds_units_and_tool(tree, tmp_path):
    wrapper = tmp_path / "arm.yaml"
    wrapper.write_text("name: wrapped\nunits: {length: mm, angle: deg}\nconvention: urdf\n"
                       "urdf: tree.urdf\ntip: hand\ntool: {xyz: [0, 0, 20]}\n")
    robot = armkit.load_robot(wrapper)
    assert robot.units.length == "mm"
    np.testing.assert_allclose(armkit.fk(robot, [0, 0])[:3, 3], [0.15, 0, 0.32], atol=1e-15)
    again = tmp_path / "elsewhere" / "again.yaml"        # the URDF path follows the new file
    again.parent.mkdir()
    armkit.save_robot(robot, again)
    np.testing.assert_allclose(armkit.fk(armkit.load_robot(again), [0.3, 0.1]),
                               armkit.fk(robot, [0.3, 0.1]), atol=1e-15)

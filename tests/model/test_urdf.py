"""URDF chains: joint types, limits, tips of a tree, and the errors."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
import armkit.io.urdf
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
    robot = armkit.model.chain_from_urdf(armkit.io.urdf.read_urdf(tree, tip="hand"))
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
        armkit.io.urdf.read_urdf(tree, tip="gripper")


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
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="yaw"/>',
     "joint 'slide' <mimic> joint: expected a joint of its own kind (prismatic), found 'yaw', "
     "continuous"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="ghost"/>',
     "joint 'slide' <mimic> joint: expected the name of a joint of the file, found 'ghost'"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="hand_mount"/>',
     "joint 'slide' <mimic> joint: expected an independent moving joint, found 'hand_mount', "
     "a fixed joint"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic/>',
     "joint 'slide' <mimic> joint: expected the name of the joint it mimics, found none"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="yaw" multiplier="true"/>',
     "joint 'slide' <mimic> multiplier: expected a finite number, found 'true'"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1 0 0"/><mimic joint="yaw" offset="1e400"/>',
     "joint 'slide' <mimic> offset: expected a finite number"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="0 0 0"/>', "<axis> xyz: expected a non-zero direction"),
    ("</robot>", "", "expected a readable URDF (XML) file"),
    ("<robot", "<sdf", "expected a <robot> root element, found <sdf>"),
])
def test_urdf_mistakes(tmp_path, old, new, words):
    path = tmp_path / "bad.urdf"
    path.write_text(TREE.replace(old, new).replace("</robot>", "</sdf>") if old == "<robot"
                    else TREE.replace(old, new))
    with pytest.raises(ModelFileError) as err:
        armkit.io.urdf.read_urdf(path, tip="hand")
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


def urdf(tmp_path, text: str, name: str = "bad.urdf"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def refused(path, words: str, tip: str | None = "hand") -> str:
    with pytest.raises(ModelFileError) as err:
        armkit.io.urdf.read_urdf(path, tip=tip)
    message = str(err.value)
    assert message.startswith(f"{path}: ") and words in message, message
    return message


@pytest.mark.parametrize("old, new, words", [
    # a link with two parents (the file's 4 joints must not load as 3)
    ("</robot>", ('<joint name="extra" type="revolute"><parent link="base"/><child link="l2"/>'
     '<limit lower="0" upper="1"/></joint></robot>'),
     "link 'l2': expected one parent joint (a tree), found two: joints 'slide' and 'extra'"),
    ('<joint name="slide"', '<joint name="yaw"', ("joint 'yaw': expected a name no other joint "
     "has, found it declared twice")),
    ('<link name="camera"/>', '<link name="camera"/><link name="l1"/>',
     "link 'l1': expected a name no other link has, found it declared twice"),
    ('<joint name="yaw" type="continuous"><parent link="base"/>',
     '<joint name="yaw" type="continuous"><parent link="bsae"/>',
     ("joint 'yaw' <parent>: expected a link declared in the file, found link 'bsae', which no "
     "<link> declares")),
    ('<child link="hand"/>', '<child/>', ("joint 'hand_mount' <child>: expected <child "
     "link=\"...\">, found none")),
    ('<joint name="yaw"', '<joint', "<joint>: expected a name attribute, found none"),
    ('<link name="camera"/>', '<link/>', "<link>: expected a name attribute, found none"),
    ('velocity="0.2"', 'velocity="nan"', ("joint 'slide' <limit> velocity: expected a finite "
     "number, found 'nan'")),
    ('velocity="0.2"', 'velocity="0"', "<limit> velocity: expected a positive number, found '0'"),
    ('velocity="0.2"', 'velocity="-1"', "<limit> velocity: expected a positive number"),
    ('velocity="0.2"', 'velocity="1e308"', ("<limit> velocity: expected a finite number of at "
     "most 1e+06 in size")),
    ('<limit lower="0" upper="0.5"', '<limit lower="0" upper="\u0661"',
     "joint 'slide' <limit> upper: expected a finite number, found '\u0661'"),
    ('<limit lower="0" upper="0.5"', '<limit lower="0" upper="1_0"',
     "<limit> upper: expected a finite number, found '1_0'"),
    ('<limit lower="0" upper="0.5"', '<limit lower="-1e308" upper="0.5"',
     "<limit> lower: expected a finite number of at most 1000 in size, found '-1e308'"),
    ('<limit lower="0" upper="0.5"', '<limit lower="0" upper="0"', "expected lower < upper"),
    ('<axis xyz="1 0 0"/>', '<axis xyz="1e308 0 0"/>',
     "joint 'slide' <axis> xyz: expected 3 finite numbers of at most 1000 in size"),
    ('xyz="0.1 0 0"', 'xyz="0.1 0 \u0664"', "<origin> xyz: expected 3 finite numbers"),
    ('xyz="0.1 0 0" rpy="0 0 0"', 'xyz="0.1 0 0" rpy="0 0 1e4"',
     "<origin> rpy: expected 3 finite numbers of at most 1000 in size"),
    ('<robot name="tree">', '<!DOCTYPE r [<!ENTITY a "aaaa">]><robot name="tree">',
     "expected a URDF (XML) file without entity declarations"),
])
def test_urdf_structure_and_number_mistakes(tmp_path, old, new, words):
    assert old in TREE
    refused(urdf(tmp_path, TREE.replace(old, new)), words)


def test_a_loop_is_named(tmp_path):
    loop = TREE.replace('<joint name="camera_mount" type="fixed"><parent link="l1"/>'
                        '<child link="camera"/>',
                        '<joint name="camera_mount" type="fixed"><parent link="camera"/>'
                        '<child link="camera"/>')
    refused(urdf(tmp_path, loop), "<joint>: expected a tree of links (no loop), found a loop "
            "through links camera, camera (joints camera_mount)")
    ring = ('<robot name="ring"><link name="a"/><link name="b"/><link name="c"/>'
            '<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
            '<joint name="bc" type="fixed"><parent link="b"/><child link="c"/></joint>'
            '<joint name="ca" type="fixed"><parent link="c"/><child link="a"/></joint></robot>')
    refused(urdf(tmp_path, ring), "found a loop through links", tip="c")   # not "0 roots"


def test_several_roots_and_no_links(tmp_path):
    refused(urdf(tmp_path, TREE.replace('<link name="camera"/>', '<link name="camera"/>'
                                        '<link name="loose"/>')),
            "<link>: expected one root link (a link no joint has as child), found 2: base, loose")
    refused(urdf(tmp_path, '<robot name="empty"></robot>'), "<link>: expected at least one link")


MIMIC_FINGER = ('<link name="finger"/><joint name="finger_joint" type="prismatic">'
                '<parent link="l2"/><child link="finger"/><axis xyz="0 1 0"/>'
                '<limit lower="0" upper="0.04" velocity="0"/><mimic joint="slide" '
                'multiplier="-1"/></joint>')


def test_joints_off_the_chain_are_ignored(tmp_path):
    # A mimic finger (with velocity="0", as real files have), a floating joint, meshes.
    text = TREE.replace("</robot>", MIMIC_FINGER + '<link name="float"/><joint name="free" '
                        'type="floating"><parent link="base"/><child link="float"/></joint>'
                        "</robot>").replace(
        '<link name="l1"/>', '<link name="l1"><visual><geometry><mesh filename="package://'
        'nowhere/meshes/l1.stl"/></geometry></visual></link>')
    table = armkit.io.urdf.read_urdf(urdf(tmp_path, text, "tree.urdf"), tip="hand")
    assert [j.name for j in table.joints] == ["yaw", "slide", "hand_mount"]
    reference = armkit.io.urdf.read_urdf(urdf(tmp_path, TREE, "plain.urdf"), tip="hand")
    q = [0.3, 0.1]
    np.testing.assert_array_equal(
        armkit.fk(armkit.Robot("a", armkit.model.chain_from_urdf(table)), q),
        armkit.fk(armkit.Robot("b", armkit.model.chain_from_urdf(reference)), q))


def test_a_mimic_joint_on_the_chain_moves_with_its_leader(tmp_path):
    # finger = -0.5 slide + 0.3, within 0 .. 0.04 m: slide within 0.52 .. 0.6 (its own 0 .. 0.7)
    finger = MIMIC_FINGER.replace('multiplier="-1"', 'multiplier="-0.5" offset="0.3"')
    text = TREE.replace('upper="0.5" velocity="0.2"', 'upper="0.7" velocity="0.2"')
    robot = armkit.load_robot(urdf(tmp_path, text.replace("</robot>", finger + "</robot>")),
                              tip="finger")
    assert robot.joint_names == ("yaw", "slide") and robot.chain.n_joints == 3
    np.testing.assert_allclose([robot.lower[1], robot.upper[1]], [0.52, 0.6], rtol=1e-15)
    q = np.array([np.pi / 2, 0.55])
    # By hand: yaw turns x onto y; slide 0.1 + 0.55 along it, then the finger -0.5 * 0.55 + 0.3
    # along the turned y (-x).
    T = transform(rotz(np.pi / 2), [-(0.3 - 0.275), 0.65, 0.3])
    np.testing.assert_allclose(armkit.fk(robot, q), T, atol=1e-15)
    batch = np.array([q, [0.2, 0.53], [-1.0, 0.58]])
    np.testing.assert_array_equal(armkit.fk(robot, batch), [armkit.fk(robot, c) for c in batch])
    J = armkit.jacobian(robot, q)
    np.testing.assert_allclose(J[:3, 1], [0.5, 1.0, 0.0], atol=1e-15)   # d(finger)/d(slide)
    qd, h = np.array([0.7, -0.2]), 1e-6
    np.testing.assert_allclose(armkit.jacobian_dot(robot, q, qd),
                               (armkit.jacobian(robot, q + h * qd)
                                - armkit.jacobian(robot, q - h * qd)) / (2 * h), atol=1e-8)
    # A mimic joint has no value of its own: the IK answer drives it through its leader.
    found = armkit.ik(robot, T, mask="position", q0=[0.0, 0.6])
    assert found.success and abs(found.q[1] - 0.55) < 1e-9


def test_the_reach_bound_counts_a_mimic_joints_stroke(tmp_path):
    # finger = 2 slide: the finger strokes 1 m as the slide strokes 0.5 m.
    finger = MIMIC_FINGER.replace('multiplier="-1"', 'multiplier="2"').replace(
        'lower="0" upper="0.04"', 'lower="-2" upper="2"')
    robot = armkit.load_robot(urdf(tmp_path, TREE.replace("</robot>", finger + "</robot>")),
                              tip="finger")
    Q = np.random.default_rng(1).uniform(*robot.sampling_limits, (2000, 2))
    Q[:, 1] = np.where(np.arange(2000) % 2, robot.lower[1], robot.upper[1])
    reach = np.linalg.norm(armkit.fk(robot, Q)[:, :3, 3] - robot.chain.points[0], axis=1)
    assert reach.max() <= armkit.IKSolver(robot).reach


def test_a_mimic_joint_whose_range_excludes_its_leaders_is_refused(tmp_path):
    # finger = -slide within 0 .. 0.04 m needs slide within -0.04 .. 0; its own is 0 .. 0.5.
    path = urdf(tmp_path, TREE.replace("</robot>", MIMIC_FINGER.replace(
        'lower="0" upper="0.04"', 'lower="0.01" upper="0.04"') + "</robot>"))
    refused(path, "joint 'slide' <limit>: expected a range in which its mimic joints "
            "(finger_joint) stay within their limits, found none", tip="finger")


def test_files_that_are_not_files(tmp_path):
    refused(tmp_path, "expected a regular file, found a directory, device or pipe")
    with pytest.raises(ModelFileError, match="/dev/zero: expected a regular file"):
        armkit.io.urdf.read_urdf("/dev/zero")


XACRO = """<?xml version="1.0"?>
<robot name="tree" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="lift" value="0.3"/>
  <xacro:macro name="bare" params="name"><link name="${name}"/></xacro:macro>
  <xacro:bare name="base"/><xacro:bare name="l1"/><xacro:bare name="l2"/>
  <xacro:bare name="hand"/><xacro:bare name="camera"/>
  <joint name="yaw" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 ${lift}"/><axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="${lift / 3} 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" velocity="0.2" effort="10"/></joint>
  <joint name="hand_mount" type="fixed"><parent link="l2"/><child link="hand"/>
    <origin xyz="0.05 0 0"/></joint>
  <joint name="camera_mount" type="fixed"><parent link="l1"/><child link="camera"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>"""


def test_xacro_file_expands_to_the_same_chain(tmp_path, tree):
    path = urdf(tmp_path, XACRO, "tree.urdf.xacro")
    robot = armkit.model.chain_from_urdf(armkit.io.urdf.read_urdf(path, tip="hand"))
    plain = armkit.model.chain_from_urdf(armkit.io.urdf.read_urdf(tree, tip="hand"))
    q = [0.7, 0.2]
    np.testing.assert_allclose(armkit.fk(armkit.Robot("x", robot), q),
                               armkit.fk(armkit.Robot("u", plain), q), atol=1e-15)
    refused(urdf(tmp_path, XACRO.replace("${lift / 3}", "${reach}"), "bad.xacro"),
            "expected a .xacro file that expands to URDF, found name 'reach' is not defined")
    find = XACRO.replace('<xacro:property name="lift" value="0.3"/>', '<xacro:include '
                         'filename="$(find franka_description)/robots/common.xacro"/>')
    refused(urdf(tmp_path, find, "find.xacro"), "found a $(find ...) package it cannot "
            "find (xacro looks packages up in a ROS installation)")


def test_xacro_without_the_package_says_how_to_get_it(tmp_path, monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "xacro", None)          # as if not installed
    refused(urdf(tmp_path, XACRO, "tree.xacro"), 'expected the xacro package to expand a .xacro '
            'file (pip install "armkit[xacro]"), found it is not installed')


def test_yaml_wrapper_naming_a_missing_urdf(tmp_path):
    wrapper = tmp_path / "arm.yaml"
    wrapper.write_text("name: w\nunits: {length: m, angle: rad}\nconvention: urdf\n"
                       "urdf: nowhere.urdf\n")
    with pytest.raises(ModelFileError, match=r"arm.yaml: urdf: expected a URDF file \(its path "
                                             r"relative to this file\), found 'nowhere.urdf', "
                                             r"which is not a file"):
        armkit.load_robot(wrapper)
